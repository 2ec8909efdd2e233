// `springy check`: runs scenes headlessly under the stability monitor and reports per body.
#include <sys/stat.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include "app/atomic_file.h"
#include "app/commands.h"
#include "app/export.h"
#include "app/run_outputs.h"
#include "run/load.h"
#include "run/run.h"
#include "sim/error.h"

namespace springy {
namespace {

enum class CheckedScene { Ok, Failed, Interrupted };

// One scene's run with its outputs (trace rows, export) and its table; `record` receives its record.
CheckedScene checkScene(const std::string& path, const CheckOptions& options, const std::vector<std::string>& inputs,
                        SceneRecord& record,
                        const std::string& exportPath, std::ofstream* trace, const std::string& traceTemporary) {
  const std::string who = "springy " + options.command + ": ";  // messages' prefix
  try {
    // The scene's one run: its observers write the trace and the export as it goes.
    Run run(path, options.run);
    RunHeader header(true);
    run.observe(header);
    std::optional<TraceRows> rows;
    if (trace) run.observe(rows.emplace(*trace, traceTemporary));
    std::optional<ExportFrames> exported;
    if (!exportPath.empty()) run.observe(exported.emplace(exportPath, inputs));
    const std::optional<Failure> failure = run.complete();
    if (interrupted()) return CheckedScene::Interrupted;
    record = run.record();
    printResults(run);
    if (exported && !failure) {
      exported->exporter()->commit();
      std::printf("  exported: %s\n", exported->exporter()->written().c_str());
    } else if (exported) {
      std::printf("  not exported: the run failed\n");
    }
    if (!failure) {
      std::printf("  ok\n");
      return CheckedScene::Ok;
    }
    std::printf("  FAILED: %s\n", failure->message.c_str());
    std::cerr << who << path << ": " << failure->message << "\n";
    return CheckedScene::Failed;
  } catch (const Error& e) {
    if (interrupted()) return CheckedScene::Interrupted;
    std::cerr << who << e.what() << "\n";
    record = SceneRecord{};
    record.path = path;
    record.scene = std::filesystem::path(path).stem().string();
    record.status = SceneRecord::Status::Error;
    record.message = e.what();
    return CheckedScene::Failed;
  }
}

}  // namespace

std::vector<std::string> exportOutputs(const std::vector<std::string>& scenes, const std::string& output,
                                       const std::string& format, const std::string& option) {
  namespace fs = std::filesystem;
  if (output.empty()) throw Error(option + ": the output's name is empty: give a file or a folder");
  const bool directory = isDirectory(output) || output.back() == '/' || scenes.size() > 1;
  if (scenes.size() > 1 && !isDirectory(output)) {
    // A name with a format's extension, or a file that exists, cannot be the folder they go to.
    std::string extension = fs::path(output).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    struct stat st {};
    if (extension == ".pc2" || extension == ".glb" || extension == ".pvd" || ::lstat(output.c_str(), &st) == 0) {
      throw Error(option + " " + output + ": " + std::to_string(scenes.size()) +
                  " scenes make one export each: give a folder (ending in '/'), not a file name");
    }
  }
  if (!directory) {
    exportFormatOf(output, option);  // a file: its extension must name a format
    return {output};
  }
  const std::string extension = "." + format;
  exportFormatOf("scene" + extension, option);
  makeDirectories(output, option);
  std::vector<std::string> outputs;
  for (const std::string& scene : scenes) {
    const std::string file = (fs::path(output) / (fs::path(scene).stem().string() + extension)).string();
    for (std::size_t j = 0; j < outputs.size(); ++j) {
      if (outputs[j] == file) throw Error(scenes[j] + " and " + scene + " would both be exported to " + file);
    }
    // The name is springy's choice, not the user's: it may replace only an export springy wrote.
    struct stat st {};
    if (::lstat(file.c_str(), &st) == 0 && !exportWrittenBySpringy(file)) {
      throw Error(file + ": exists and was not written by springy (" + option + " " + output + " exports " + scene +
                  " to it); refusing to replace it. Move it away, or name another folder");
    }
    outputs.push_back(file);
  }
  return outputs;
}

int runCheck(const CheckOptions& options) {
  const std::vector<std::string> exports =
      options.exportOutput.empty()
          ? std::vector<std::string>{}
          : exportOutputs(options.scenes, options.exportOutput, options.exportFormat, options.exportOption);
  // Every file the scenes read, known before any run: no output replaces one.
  const std::vector<std::string> inputs = sceneInputFiles(options.scenes, options.run.sets);
  std::unique_ptr<AtomicFile> traceFile;
  std::ofstream trace;
  if (!options.trace.empty()) {
    traceFile = std::make_unique<AtomicFile>(options.trace, inputs);  // never over a scene or its mesh
    trace.open(traceFile->temporaryPath());
    writeTraceHeader(trace);
  }
  // Checked before any run: an unwritable --json or --junit fails at once, and no scene is replaced.
  std::unique_ptr<AtomicFile> jsonFile, junitFile;
  if (!options.json.empty()) jsonFile = std::make_unique<AtomicFile>(options.json, inputs);
  if (!options.junit.empty()) junitFile = std::make_unique<AtomicFile>(options.junit, inputs);
  std::vector<SceneRecord> records;
  int failures = 0;
  for (std::size_t sceneIndex = 0; sceneIndex < options.scenes.size(); ++sceneIndex) {
    const std::string& path = options.scenes[sceneIndex];
    const CheckedScene checked = checkScene(path, options, inputs, records.emplace_back(), exports.empty() ? "" : exports[sceneIndex],
                                            trace.is_open() ? &trace : nullptr,
                                            traceFile ? traceFile->temporaryPath() : std::string());
    if (checked == CheckedScene::Interrupted) {
      std::cerr << "springy " << options.command << ": interrupted\n";
      return interruptedExitStatus();
    }
    failures += checked == CheckedScene::Ok ? 0 : 1;
  }
  if (traceFile) {
    trace.close();
    if (!trace) throw Error(options.trace + ": writing the trace failed: " + errorText(errno));
    traceFile->commit();
  }
  if (jsonFile) {
    jsonFile->write(recordsJson(records));
    jsonFile->commit();
  }
  if (junitFile) {
    junitFile->write(junitXml(records));
    junitFile->commit();
  }
  if (options.records) *options.records = std::move(records);
  return failures == 0 ? 0 : 1;
}

}  // namespace springy
