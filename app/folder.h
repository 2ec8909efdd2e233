// springy app: output folders that appear complete or not at all (the VTK series' frames, a
// report). A folder is built under a hidden temporary name beside its target and renamed into
// place when complete; an earlier one of springy's (it holds springy's marker file) is replaced
// then, a folder that springy did not make is never touched. Like AtomicFile, every failure is a
// springy::Error naming the folder and the reason; nothing is left behind by a failure or a
// signal (the temporary folder is removed by its destructor).
#pragma once

#include <string>

namespace springy {

// Removes `path` and everything under it; errors are ignored (cleaning up after a failure).
void removeTree(const std::string& path);

class OutputFolder {
 public:
  // Checks `target` (an existing entry must be a directory holding `marker`: what springy wrote
  // there before; `what` names it in the message, e.g. "-o report") and creates the temporary
  // folder beside it, holding the marker file with `markerText`. Throws springy::Error.
  OutputFolder(std::string target, std::string marker, const std::string& markerText, const std::string& what);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::string& temporaryPath() const { return temporary_; }
  const std::string& target() const { return target_; }
  // Flushes everything under the folder to the disk, moves an earlier folder aside, renames the
  // temporary folder into place and removes the earlier one. Throws springy::Error (the earlier
  // folder is put back).
  void commit();

 private:
  [[noreturn]] void fail(const std::string& what, int error) const;
  std::string target_, marker_, what_, temporary_;
};

}  // namespace springy
