// springy app: the outputs of a run that several commands share, as observers of the run
// (run/run.h RunObserver) and its printed table: check's trace rows, an export of the motion, the
// run's header and progress on the console.
#pragma once

#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/export.h"
#include "app/progress.h"
#include "run/run.h"

namespace springy {

// check --trace: a header, then a row per frame and body. A run that starts over (the default
// step's retry) takes its rows back: the file is cut to where the scene's rows began.
void writeTraceHeader(std::ostream& out);
class TraceRows : public RunObserver {
 public:
  TraceRows(std::ofstream& out, std::string temporaryPath) : out_(out), path_(std::move(temporaryPath)) {}
  void started(const Run& run) override;
  void frame(const Run& run) override;

 private:
  std::ofstream& out_;
  std::string path_;
  std::streampos begin_{};
  bool begun_ = false;
};

// The run's motion (app/export.h), opened anew each time the run starts: a failed try's output
// goes. `open` is openExport, or openReplay for a report's page.
class ExportFrames : public RunObserver {
 public:
  using Opener = std::unique_ptr<MotionExport> (*)(const std::string&, const SceneDesc&, const World&, long, double,
                                                   const std::vector<std::string>&);
  ExportFrames(std::string path, std::vector<std::string> inputs, Opener open = openExport)
      : path_(std::move(path)), inputs_(std::move(inputs)), open_(open) {}
  void started(const Run& run) override;
  void frame(const Run& run) override;
  MotionExport* exporter() { return exporter_.get(); }

 private:
  std::string path_;
  std::vector<std::string> inputs_;
  Opener open_;
  std::unique_ptr<MotionExport> exporter_;
};

// The run's header on stdout when it starts (the scene, its step, its stages) and, with
// `progress`, its progress on stderr (a bar on a terminal, a line every 5 s in a log).
class RunHeader : public RunObserver {
 public:
  explicit RunHeader(bool progress) : showProgress_(progress) {}
  void started(const Run& run) override;
  void frame(const Run& run) override;

 private:
  bool showProgress_;
  std::optional<Progress> progress_;
};

// check's table of a finished run: a row per body, then what each solver did.
void printResults(const Run& run);

}  // namespace springy
