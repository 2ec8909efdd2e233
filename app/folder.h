// springy app: output folders that appear complete or not at all (the VTK series' frames, a
// report). A folder is built under a hidden temporary name beside its target and renamed into
// place when complete. Its marker file lists what springy wrote there (each file with its size
// and a hash of its bytes): an earlier folder of springy's is replaced only while it holds
// nothing else, so a file the user added to it (or changed) is never lost: the command refuses
// before it runs, naming those files. A folder that springy did not make is never touched. Like
// AtomicFile, every failure is a springy::Error naming the folder and the reason; nothing is
// left behind by a failure or a signal (the temporary folder is removed by its destructor, or
// by the signal's handler: registerTemporary).
#pragma once

#include <string>
#include <vector>

namespace springy {

// Removes `path` and everything under it; errors are ignored (cleaning up after a failure).
void removeTree(const std::string& path);

class OutputFolder {
 public:
  // Checks `target`: an existing entry must be an empty directory, or one holding `marker` (what
  // springy wrote there before) and nothing that the marker does not list; it must hold none of
  // `inputs` (the files the run reads). `what` names it in messages, e.g. "-o report". Then
  // creates the temporary folder beside it, holding the marker file with `markerText`. Throws
  // springy::Error.
  OutputFolder(std::string target, std::string marker, const std::string& markerText, const std::string& what,
               const std::vector<std::string>& inputs = {});
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::string& temporaryPath() const { return temporary_; }
  const std::string& target() const { return target_; }
  // Lists what was written in the marker, flushes everything under the folder to the disk, checks
  // the earlier folder again (a file added to it during the run), moves it aside, renames the
  // temporary folder into place and removes the earlier one's listed files. Throws springy::Error
  // (the earlier folder is put back).
  void commit();

 private:
  [[noreturn]] void fail(const std::string& what, int error) const;
  // Throws unless the existing target is empty or holds only what its marker lists.
  void refuseForeign() const;
  std::string target_, marker_, markerText_, what_, temporary_;
  int registered_ = -1;  // registerTemporary's handle
};

}  // namespace springy
