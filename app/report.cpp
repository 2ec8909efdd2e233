// `springy report`: one folder of HTML pages per set of runs (docs/report.md).
//
//   DIR/index.html            the overview: a row per scene (status, step, figures, contact sheet),
//                             and links to the sweep's and the study's pages
//   DIR/SCENE/index.html      a scene's page: its video, 3D replay, contact sheet, plots over time
//                             (energy, volume, strain, contacts), check's table, its files
//   DIR/sweep/index.html      a sweep's table (a row per task) and a plot of a figure against a key;
//                             DIR/sweep/task-NNNN.html per task
//   DIR/study/*.html          a study's Markdown pages with their plots
//   DIR/assets/               the pages' style and the 3D viewer (three.js, bundled)
// A page uses only files in the folder (no network), so the folder can be zipped, mailed, or
// opened from a USB stick. Each scene is run once (run/run.h): its video and contact sheet are
// drawn from the run's frames while its trace, records, replay and plots are taken from the same
// frames. The folder is built under a temporary name and renamed when complete
// (OutputFolder): a failure or a signal leaves the earlier report as it was, and a file that the
// user added to it stops the report before it runs (nothing is lost).
#include <cmark-gfm-core-extensions.h>
#include <cmark-gfm.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <cstring>

#include "app/atomic_file.h"
#include "app/child.h"
#include "app/commands.h"
#include "app/folder.h"
#include "app/frame_pipeline.h"
#include "app/gnuplot.h"
#include "app/run_outputs.h"
#include "app/scene_view.h"
#include "render/image.h"
#include "render/video_encoder.h"
#include "run/load.h"
#include "run/records.h"
#include "run/run.h"
#include "sim/error.h"

// The pages' style and the bundled viewer, embedded by app/report_assets.cpp.
extern "C" const char springy_report_viewer[], springy_report_viewer_end[];
extern "C" const char springy_report_style[], springy_report_style_end[];

namespace springy {
namespace {

namespace fs = std::filesystem;

constexpr const char* kMarker = ".springy-report";
constexpr std::size_t kMaxBodiesDrawnApart = 8;  // more bodies: the plots show the extremes over them


// A path inside a page's href or src: each byte that is not safe in a URL as %XX.
std::string urlPath(const std::string& path) {
  std::string out;
  for (unsigned char c : path) {
    if (std::isalnum(c) || std::strchr("-._~/", c)) {
      out += static_cast<char>(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    }
  }
  return out;
}

std::string number(double v, const char* format = "%.4g") {
  if (!std::isfinite(v)) return "-";
  char text[48];
  std::snprintf(text, sizeof text, format, v);
  return text;
}

std::string exact(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

void writeText(const fs::path& path, const std::string& text) { writeFileAtomically(path.string(), text); }

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot read it");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void copyFile(const fs::path& from, const fs::path& to) { writeText(to, readText(from)); }

std::string pageHead(const std::string& title, const std::string& assets) {
  return "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>" +
         xmlEscaped(title) + "</title>\n<link rel=\"stylesheet\" href=\"" + assets + "report.css\">\n</head>\n<body>\n";
}

std::string badge(bool ok, const std::string& text) {
  return std::string("<span class=\"") + (ok ? "ok" : "bad") + "\">" + xmlEscaped(text) + "</span>";
}

const char* kSvgTerminal =
    "set terminal svg size 640,340 dynamic font 'DejaVu Sans,11' background rgb 'white'\n"
    "set termoption noenhanced\nset grid lc rgb '#dddddd'\nset key top right\nset border lc rgb '#555555'\n";

// What the scene's page plots, one sample per frame.
struct Series {
  struct Body {
    std::string name;
    bool closed = false;
    double restVolume = 0.0;
  };
  std::vector<Body> bodies;
  std::size_t vertices = 0;
  std::vector<double> time;
  std::vector<double> kinetic, gravitational, elastic;  // summed over the bodies [J]
  std::vector<std::vector<double>> volume, strain, contacts;  // [frame][body]

  void clear() { *this = Series{}; }
  void add(const World& world, const Monitor& monitor) {
    const auto& info = world.model().bodies;
    if (bodies.empty()) {
      for (const BodyInfo& b : info) bodies.push_back({b.name, b.restVolume > 0.0, b.restVolume});
      vertices = world.model().vertexCount();
    }
    time.push_back(world.time());
    double k = 0, g = 0, e = 0;
    std::vector<double> vol, str, con;
    for (uint32_t b = 0; b < info.size(); ++b) {
      const BodyMeasures& m = monitor.records()[b].last;
      k += m.kinetic, g += m.gravitational, e += m.elastic;
      vol.push_back(bodies[b].closed ? m.volume / bodies[b].restVolume : std::numeric_limits<double>::quiet_NaN());
      str.push_back(m.maxStrain);
      con.push_back(touchingVertices(world, b));
    }
    kinetic.push_back(k), gravitational.push_back(g), elastic.push_back(e);
    volume.push_back(std::move(vol)), strain.push_back(std::move(str)), contacts.push_back(std::move(con));
  }
};

// series.dat and plots.gp beside the page, and the four SVGs gnuplot draws from them.
void writePlots(const fs::path& dir, const Series& s) {
  const std::size_t n = s.bodies.size();
  const bool apart = n <= kMaxBodiesDrawnApart;
  std::string dat = "# springy report: one row per frame. time [s], kinetic, gravitational, elastic, total [J]";
  if (apart) {
    dat += "; then per body: volume / rest, largest strain, vertices in contact\n";
  } else {
    dat += "; then over the " + std::to_string(n) +
           " bodies: the lowest volume / rest, the largest strain, vertices in contact in all\n";
  }
  for (std::size_t f = 0; f < s.time.size(); ++f) {
    dat += exact(s.time[f]) + " " + exact(s.kinetic[f]) + " " + exact(s.gravitational[f]) + " " + exact(s.elastic[f]) +
           " " + exact(s.kinetic[f] + s.gravitational[f] + s.elastic[f]);
    const auto field = [](double v) { return std::isfinite(v) ? " " + exact(v) : std::string(" NaN"); };
    if (apart) {
      for (std::size_t b = 0; b < n; ++b) {
        dat += field(s.volume[f][b]) + field(s.strain[f][b]) + field(s.contacts[f][b]);
      }
    } else {
      double lowest = std::numeric_limits<double>::infinity(), largest = 0.0, touching = 0.0;
      for (std::size_t b = 0; b < n; ++b) {
        if (std::isfinite(s.volume[f][b])) lowest = std::min(lowest, s.volume[f][b]);
        largest = std::max(largest, s.strain[f][b]);
        touching += s.contacts[f][b];
      }
      dat += field(std::isinf(lowest) ? std::numeric_limits<double>::quiet_NaN() : lowest) + field(largest) +
             field(touching);
    }
    dat += "\n";
  }
  writeText(dir / "series.dat", dat);

  const bool anyClosed = std::any_of(s.bodies.begin(), s.bodies.end(), [](const Series::Body& b) { return b.closed; });
  std::string gp = std::string("# springy report: the plots of this page (gnuplot plots.gp)\n") + kSvgTerminal +
                   "set xlabel 'time [s]'\nset datafile missing 'NaN'\n";
  gp += "set output 'energy.svg'\nset title 'Energy (all bodies)'\nset ylabel 'energy [J]'\n"
        "plot 'series.dat' using 1:2 with lines lw 2 title 'kinetic', '' using 1:3 with lines lw 2 title "
        "'gravitational', '' using 1:4 with lines lw 2 title 'elastic', '' using 1:5 with lines lw 2 lc rgb "
        "'black' title 'total'\n";
  const auto perBody = [&](const char* file, const char* title, const char* ylabel, int column, bool closedOnly,
                           const std::string& aggregate) {
    gp += std::string("set output '") + file + "'\nset title '" + title + "'\nset ylabel '" + ylabel + "'\nplot ";
    if (!apart) {
      gp += "'series.dat' using 1:" + std::to_string(6 + column) + " with lines lw 2 title " + gnuplotText(aggregate) +
            "\n";
      return;
    }
    bool first = true;
    for (std::size_t b = 0; b < n; ++b) {
      if (closedOnly && !s.bodies[b].closed) continue;
      gp += std::string(first ? "" : ", ") + "'series.dat' using 1:" + std::to_string(6 + 3 * b + column) +
            " with lines lw 2 title " + gnuplotText(s.bodies[b].name);
      first = false;
    }
    gp += "\n";
  };
  if (anyClosed) {
    perBody("volume.svg", "Volume", "volume / rest", 0, true, "lowest of " + std::to_string(n) + " bodies");
  }
  perBody("strain.svg", "Largest strain", "|l - l0| / l0", 1, false, "largest of " + std::to_string(n) + " bodies");
  perBody("contacts.svg", "Contacts", "vertices touching", 2, false, "all " + std::to_string(n) + " bodies");
  writeText(dir / "plots.gp", gp);
  runGnuplot(dir / "plots.gp");
}

struct SceneResult {
  std::string path, stem;
  SceneRecord record;
  bool motion = false;  // the replay, the video and the sheet were written (the motion is valid)
  std::size_t vertices = 0;
};

std::string checkTable(const SceneRecord& r, const ReportOptions& o) {
  std::string t = "<table class=\"check\">\n<tr><th>body</th><th>steps</th><th>max strain</th><th>max pen. [m]</th>"
                  "<th>volume min</th><th>volume end</th><th>kinetic [J]</th><th>elastic [J]</th><th>at rest</th>"
                  "<th>result</th></tr>\n";
  for (std::size_t b = 0; b < r.bodies.size(); ++b) {
    const BodyResult& body = r.bodies[b];
    const bool failedHere = r.status != SceneRecord::Status::Ok && r.failedBody && *r.failedBody == b;
    const auto volume = [](const std::optional<double>& v, double least) {
      if (!v) return std::string("<td>-</td>");
      const std::string cls = least <= 0.0 ? "" : *v >= least ? " class=\"ok\"" : " class=\"bad\"";
      return "<td" + cls + ">" + number(*v, std::abs(*v) < 1e3 ? "%.3f" : "%.3g") + "</td>";
    };
    const std::string rest = o.run.endAtRest ? (body.atRest ? " class=\"ok\"" : " class=\"bad\"") : "";
    t += "<tr><td>" + xmlEscaped(body.name) + "</td><td>" + std::to_string(body.steps) + "</td><td>" +
         number(body.maxStrain) + "</td><td>" + number(body.maxPenetration, "%.2e") + "</td>" +
         volume(body.volumeMin, o.run.minVolume) + volume(body.volumeEnd, o.run.endVolume) + "<td>" + number(body.kinetic) +
         "</td><td>" + number(body.elastic) + "</td><td" + rest + ">" + (body.atRest ? "yes" : "no") + "</td>" +
         (failedHere ? "<td class=\"bad\">failed</td>" : r.status == SceneRecord::Status::Ok ? "<td class=\"ok\">ok</td>"
                                                                                              : "<td>-</td>") +
         "</tr>\n";
  }
  return t + "</table>\n";
}

std::string criteriaText(const ReportOptions& o) {
  std::string c = "stable (no NaN, no body past 10&times; its size, no energy gained from nothing, no vertex behind "
                  "a plane)";
  if (o.run.minVolume > 0) c += "; volume &ge; " + number(o.run.minVolume) + " of rest throughout";
  if (o.run.endVolume > 0) c += "; volume &ge; " + number(o.run.endVolume) + " of rest at the end";
  if (o.run.endAtRest) c += "; at rest over the last second";
  return c;
}

std::string stepText(const SceneRecord& r) {
  if (r.dt <= 0) return "-";
  return number(r.dt, "%.4g") + " s" + (r.substeps > 1 ? " in " + std::to_string(r.substeps) + " substeps (" +
                                                            number(r.dt / r.substeps, "%.4g") + " s each)"
                                                      : std::string());
}

void writeScenePage(const fs::path& dir, const SceneResult& s, const ReportOptions& o, const Series& series) {
  const SceneRecord& r = s.record;
  const bool ok = r.status == SceneRecord::Status::Ok;
  std::string page = pageHead("springy report: " + r.scene, "../assets/");
  page += "<header><h1>" + xmlEscaped(r.scene) + "</h1><p>" + xmlEscaped(s.path) +
          " &middot; <a href=\"../index.html\">all of the report</a></p></header>\n<main>\n";
  page += "<section><h2>Result " + badge(ok, statusName(r.status)) + "</h2>\n";
  if (!r.message.empty()) page += "<div class=\"message\">" + xmlEscaped(r.message) + "</div>\n";
  page += "<dl class=\"facts\"><dt>integrator</dt><dd>" + xmlEscaped(r.integrator.empty() ? "-" : r.integrator) +
          "</dd><dt>step</dt><dd>" + stepText(r) + "</dd><dt>simulated</dt><dd>" + number(r.duration) + " s" +
          (ok || series.time.empty() || series.time.back() >= r.duration - 1e-6 ? std::string() : ", stopped at " + number(series.time.back()) + " s") +
          "</dd><dt>bodies</dt><dd>" + std::to_string(r.bodies.size()) + " (" + std::to_string(s.vertices) +
          " vertices)</dd>";
  if (!r.bodies.empty()) page += "<dt>steps</dt><dd>" + std::to_string(r.bodies[0].steps) + "</dd>";
  page += "<dt>wall time</dt><dd>" + number(r.wall, "%.3g") + " s (the run, drawn and written)</dd><dt>criteria</dt><dd>" +
          criteriaText(o) + "</dd></dl>\n</section>\n";
  if (s.motion) {
    page += "<section class=\"grid\">\n<div><h2>Video</h2>\n<video id=\"video\" controls muted playsinline "
            "preload=\"auto\" src=\"" +
            urlPath(s.stem + ".mp4") +
            "\"></video></div>\n<div class=\"springy-replay\" data-video=\"video\"><h2>3D replay</h2>\n"
            "<div class=\"springy-replay-canvas\"></div>\n<div class=\"controls\"><button type=\"button\" "
            "class=\"springy-replay-play\">Play</button><input type=\"range\" class=\"springy-replay-time\" min=\"0\" "
            "max=\"0\" value=\"0\" aria-label=\"time\"><span class=\"springy-replay-label\">loading&hellip;</span>"
            "<label><input type=\"checkbox\" class=\"springy-replay-follow\"> follow the video</label></div>\n"
            "<p class=\"files\">Drag to turn, scroll to zoom, right-drag to pan.</p></div>\n</section>\n";
    page += "<section class=\"sheet\"><h2>Contact sheet</h2><img src=\"" + urlPath(s.stem + "_sheet.png") +
            "\" alt=\"stills of " + xmlEscaped(r.scene) + " at eight times\"></section>\n";
  } else if (r.status != SceneRecord::Status::Error) {
    page += "<section><h2>Video</h2><p>No video: the run is not a valid motion (springy shows no video of an "
            "unstable run). The plots below go up to where it stopped.</p></section>\n";
  }
  if (!series.time.empty()) {
    page += "<section><h2>Over time</h2>\n<div class=\"plots\">";
    for (const char* plot : {"energy", "volume", "strain", "contacts"}) {
      if (fs::exists(dir / (std::string(plot) + ".svg"))) {
        page += std::string("<img src=\"") + plot + ".svg\" alt=\"" + plot + " over time\">";
      }
    }
    page += "</div>\n</section>\n";
  }
  if (!r.bodies.empty()) page += "<section><h2>Check</h2>\n" + checkTable(r, o) + "</section>\n";
  page += "<section><h2>Files</h2><ul class=\"files\">";
  const auto file = [&](const std::string& name, const std::string& what) {
    if (fs::exists(dir / name)) page += "<li><a href=\"" + urlPath(name) + "\">" + xmlEscaped(name) + "</a>: " + what + "</li>";
  };
  file(s.stem + ".mp4", "the video (H.264)");
  file("trace.csv", "check's trace: per frame and body, centroid, volume, energies, strain, contacts");
  file("check.json", "check's results (as <code>check --json</code>)");
  file("series.dat", "the plotted numbers");
  file("plots.gp", "the plots' gnuplot script");
  file("scene.toml", "the scene file as it was run");
  page += "</ul></section>\n</main>\n";
  if (s.motion) page += "<script src=\"replay.js\"></script>\n<script src=\"../assets/viewer.js\"></script>\n";
  page += "</body>\n</html>\n";
  writeText(dir / "index.html", page);
}

// The plots' numbers: the run's measures at each frame (a run that starts over starts them over).
class SeriesFrames : public RunObserver {
 public:
  explicit SeriesFrames(Series& series) : series_(series) {}
  void started(const Run&) override { series_.clear(); }
  void frame(const Run& run) override { series_.add(run.world(), run.monitor()); }

 private:
  Series& series_;
};

// The drawn frames to the video's encoder, and the contact sheet's stills: the frames nearest the
// sheet's eight times (sheetTimes), at half the video's size (eight make a sheet twice its width).
class VideoAndSheet : public FrameSink {
 public:
  VideoAndSheet(render::VideoEncoder& encoder, const Run& run) : encoder_(encoder) {
    const RenderDesc& r = run.scene().view.render;
    width_ = r.width, height_ = r.height;
    for (double t : sheetTimes(run.scene().duration)) {
      const long k = std::clamp(std::lround(t / run.frameTime()), 0L, run.frames() - 1);
      char label[64];
      std::snprintf(label, sizeof label, "t = %.2f s", static_cast<double>(k) * run.frameTime());
      wanted_.push_back(k);
      labels_.push_back(label);
    }
    stills_.resize(wanted_.size());
  }
  void write(long k, const std::vector<uint8_t>& rgba) override {
    encoder_.writeFrame(rgba, render::RowOrder::BottomUp);
    for (std::size_t i = 0; i < wanted_.size(); ++i) {
      if (wanted_[i] == k) stills_[i] = halved(rgba);
    }
  }
  render::Image sheet() const { return render::makeContactSheet(stills_, labels_, sheetOptions(stills_.size())); }

 private:
  // The frame at half its size (each pixel the mean of four), rows top-down.
  render::Image halved(const std::vector<uint8_t>& rgba) const {
    render::Image out;
    out.width = width_ / 2, out.height = height_ / 2;
    out.rgba.resize(static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height) * 4);
    const auto at = [&](int x, int y, int c) {
      return static_cast<unsigned>(rgba[(static_cast<std::size_t>(height_ - 1 - y) * static_cast<std::size_t>(width_) +
                                         static_cast<std::size_t>(x)) * 4 + static_cast<std::size_t>(c)]);
    };
    for (int y = 0; y < out.height; ++y) {
      for (int x = 0; x < out.width; ++x) {
        for (int c = 0; c < 4; ++c) {
          const unsigned sum = at(2 * x, 2 * y, c) + at(2 * x + 1, 2 * y, c) + at(2 * x, 2 * y + 1, c) +
                               at(2 * x + 1, 2 * y + 1, c);
          out.rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(out.width) + static_cast<std::size_t>(x)) * 4 +
                   static_cast<std::size_t>(c)] = static_cast<uint8_t>((sum + 2) / 4);
        }
      }
    }
    return out;
  }

  render::VideoEncoder& encoder_;
  int width_ = 0, height_ = 0;
  std::vector<long> wanted_;
  std::vector<std::string> labels_;
  std::vector<render::Image> stills_;
};

// The scene's run, drawn: the video and the sheet from the pipeline, the observers' outputs
// (trace, replay, plots) from the same frames. Again from the start when the default step's try
// fails. Returns false when interrupted.
bool drawRun(Run& run, const fs::path& dir, const std::string& stem) {
  const SceneDesc& scene = run.scene();
  const RenderEnvironment env = RenderEnvironment::read();
  for (;;) {
    SceneView view(scene, run.world(), renderSettingsOf(scene));
    render::VideoEncoder::setLibraryLogging(false);
    render::VideoEncoder encoder;
    const std::string video = (dir / (stem + ".mp4")).string();
    encoder.open(video, videoSettingsOf(scene, env));
    VideoAndSheet sink(encoder, run);
    const FramePipelineSettings settings{scene.name, scene.view.render.width, scene.view.render.height, env.serial};
    const FramePipelineResult result = runFramePipeline(run, view, sink, settings, &encoder);
    if (result.interrupted || interrupted()) return false;
    if (run.failure() && run.retry()) continue;
    if (!run.failure()) run.judgeEnd();
    // A run that failed only a criterion (--end-at-rest, --end-volume) is a valid motion: its video
    // is shown beside the failure. An unstable one has none.
    if (run.failure() && !run.failure()->criterion) {
      fs::remove(video);
      return true;
    }
    encoder.finish();
    AtomicFile sheet((dir / (stem + "_sheet.png")).string());
    sheet.write(render::encodePng(sink.sheet()));
    sheet.commit();
    return true;
  }
}

// One scene: its run (the video, the sheet, the trace, the record, the replay and the plots all
// from it), then the page. Returns false when interrupted.
bool reportScene(const fs::path& root, SceneResult& s, const ReportOptions& o) {
  const fs::path dir = root / s.stem;
  makeDirectories(dir.string(), "report");
  if (fs::exists(s.path)) copyFile(s.path, dir / "scene.toml");
  Series series;
  try {
    Run run(s.path, o.run, renderEdit(RenderOverrides{}));
    RunHeader header(false);
    run.observe(header);
    AtomicFile traceFile((dir / "trace.csv").string(), {s.path});
    std::ofstream trace(traceFile.temporaryPath());
    writeTraceHeader(trace);
    TraceRows rows(trace, traceFile.temporaryPath());
    run.observe(rows);
    ExportFrames replay((dir / "replay.js").string(), {s.path}, openReplay);
    run.observe(replay);
    SeriesFrames plotted(series);
    run.observe(plotted);
    if (!drawRun(run, dir, s.stem)) return false;
    trace.close();
    traceFile.commit();
    s.record = run.record();
    printResults(run);
    std::printf("  %s\n", run.failure() ? ("FAILED: " + run.failure()->message).c_str() : "ok");
    s.motion = !run.failure() || run.failure()->criterion;
    if (s.motion) replay.exporter()->commit();
    writeFileAtomically((dir / "check.json").string(), recordsJson({s.record}));
  } catch (const Error& e) {
    if (interrupted()) return false;
    std::cerr << "springy report: " << e.what() << "\n";
    s.record = SceneRecord{};
    s.record.path = s.path;
    s.record.scene = s.stem;
    s.record.status = SceneRecord::Status::Error;
    s.record.message = e.what();
  }
  s.vertices = series.vertices;
  if (!series.time.empty()) writePlots(dir, series);
  writeScenePage(dir, s, o, series);
  return !interrupted();
}

// ---- a sweep -------------------------------------------------------------------------------

// A task's member, or an empty array or object where it has none (a reference: never a temporary
// to loop over).
const Json& member(const Json& t, const char* key, bool array) {
  static const Json kArray = Json::array(), kObject = Json::object();
  return t.contains(key) ? t[key] : array ? kArray : kObject;
}

// A task's figure: over its bodies, the lowest volume or the largest of the rest.
std::optional<double> taskFigure(const Json& task, const std::string& figure) {
  std::optional<double> out;
  if (!task.contains("records")) return out;
  for (const Json& record : task["records"]) {
    for (const Json& body : member(record, "bodies", true)) {
      const Json* v = body.contains(figure) ? &body[figure] : nullptr;
      if (!v || !v->is_number()) continue;
      const double x = v->get<double>();
      const bool lowest = figure.rfind("volume", 0) == 0;
      out = !out ? x : lowest ? std::min(*out, x) : std::max(*out, x);
    }
  }
  return out;
}

std::string jsonText(const Json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_float()) return number(v.get<double>(), "%.6g");
  return v.dump();
}

// A sweep's table (FROM/table.json), read and checked to hold tasks.
Json readSweepTable(const fs::path& from, const std::string& sweepOption) {
  const fs::path tableFile = from / "table.json";
  if (!fs::exists(tableFile)) {
    throw Error("--sweep " + sweepOption + ": no table.json there (is it a sweep's folder? `springy gather " +
                (from / "manifest.jsonl").string() + "` writes it)");
  }
  Json table;
  try {
    table = Json::parse(readText(tableFile));
  } catch (const Json::exception& e) {
    throw Error(tableFile.string() + ": not a sweep's table: " + e.what());
  }
  if (!table.contains("tasks") || !table["tasks"].is_array()) throw Error(tableFile.string() + ": no \"tasks\" in it");
  return table;
}

// What a sweep's page shows: the tasks' keys, those swept, and its plot's axes (a line per value
// of `series`, the other swept key, when x is swept too).
struct SweepAxes {
  std::vector<std::string> keys, swept;
  std::string x, y, series;
};

// The tasks' keys and the plot's axes, from --x and --y; throws for a key or figure the table lacks.
SweepAxes sweepAxes(const Json& tasks, const ReportOptions& o) {
  SweepAxes a;
  // The keys, in the first task's order; those that take more than one value are swept.
  std::map<std::string, std::set<std::string>> values;
  for (const Json& t : tasks) {
    for (const auto& [key, value] : member(t, "point", false).items()) {
      if (std::find(a.keys.begin(), a.keys.end(), key) == a.keys.end()) a.keys.push_back(key);
      values[key].insert(value.dump());
    }
  }
  for (const std::string& k : a.keys) {
    if (values[k].size() > 1) a.swept.push_back(k);
  }
  a.x = !o.x.empty() ? o.x : a.swept.empty() ? std::string() : a.swept[0];
  if (!o.x.empty() && std::find(a.keys.begin(), a.keys.end(), o.x) == a.keys.end()) {
    std::string known;
    for (const std::string& k : a.keys) known += (known.empty() ? "" : ", ") + k;
    throw Error("--x " + o.x + ": the sweep has no such key (its keys: " + known + ")");
  }
  a.y = o.y.empty() ? "volume_min" : o.y;
  const std::vector<std::string> figures = {"volume_min", "volume_end", "max_strain", "max_penetration", "steps",
                                            "kinetic", "elastic"};
  if (std::find(figures.begin(), figures.end(), a.y) == figures.end()) {
    throw Error("--y " + a.y + ": not a figure of the table; give volume_min, volume_end, max_strain, max_penetration, "
                "steps, kinetic or elastic");
  }
  a.series = std::find(a.swept.begin(), a.swept.end(), a.x) != a.swept.end() && a.swept.size() > 1
                 ? (a.swept[0] == a.x ? a.swept[1] : a.swept[0])
                 : std::string();
  return a;
}

// A task's page in the sweep's folder: task-NNNN.html.
std::string taskPageName(long index) {
  char name[32];
  std::snprintf(name, sizeof name, "task-%04ld.html", index);
  return name;
}

// A task's row of the sweep's table: its page, scene, point, status, figures and message.
std::string taskRow(const Json& t, long index, const std::string& status, bool ok,
                    const std::vector<std::string>& keys) {
  const Json& point = member(t, "point", false);
  std::string row = "<tr><td><a href=\"" + taskPageName(index) + "\">" + std::to_string(index) + "</a></td><td>" +
                    xmlEscaped(t.value("scene", std::string())) + "</td>";
  for (const std::string& k : keys) {
    row += "<td>" + (point.contains(k) ? xmlEscaped(jsonText(point[k])) : "-") + "</td>";
  }
  row += std::string("<td class=\"") + (ok ? "ok" : "bad") + "\">" + xmlEscaped(status) + "</td>";
  for (const char* f : {"volume_min", "max_strain", "max_penetration", "steps"}) {
    const std::optional<double> v = taskFigure(t, f);
    row += "<td>" + (v ? number(*v, std::strcmp(f, "steps") == 0 ? "%.0f" : "%.4g") : "-") + "</td>";
  }
  row += "<td class=\"message\">" + xmlEscaped(t.value("message", std::string())) + "</td></tr>\n";
  return row;
}

// The plot's points ("x y" lines) per value of the series: [0] of the tasks that are ok, [1] of the rest.
using SweepLines = std::array<std::map<std::string, std::string>, 2>;

// Adds a task's point to its series' line, where the task has the figure and a number for x.
void addSweepPoint(std::map<std::string, std::string>& lines, const Json& t, const SweepAxes& a) {
  const Json& point = member(t, "point", false);
  const std::optional<double> fy = taskFigure(t, a.y);
  if (!a.x.empty() && point.contains(a.x) && point[a.x].is_number() && fy) {
    const std::string s = a.series.empty() ? "" : point.contains(a.series) ? jsonText(point[a.series]) : "-";
    lines[s] += exact(point[a.x].get<double>()) + " " + exact(*fy) + "\n";
  }
}

// Writes a task's page: its point, command, result (check's tables) and log.
void writeTaskPage(const fs::path& dir, const fs::path& from, const std::string& tableFile, const Json& t, long index,
                   const std::string& status, bool ok) {
  const Json& point = member(t, "point", false);
  std::string page = pageHead("springy sweep task " + std::to_string(index), "../assets/");
  page += "<header><h1>Task " + std::to_string(index) + " " + badge(ok, status) + "</h1><p>" +
          xmlEscaped(t.value("scene", std::string())) + " &middot; <a href=\"index.html\">the sweep</a> &middot; <a "
          "href=\"../index.html\">all of the report</a></p></header>\n<main>\n<section><h2>Point</h2><dl class=\"facts\">";
  for (const auto& [k, v] : point.items()) {
    page += "<dt>" + xmlEscaped(k) + "</dt><dd>" + xmlEscaped(jsonText(v)) + "</dd>";
  }
  page += "</dl>\n<h3>command</h3><pre>springy";
  for (const Json& a : member(t, "command", true)) page += " " + xmlEscaped(jsonText(a));
  page += "</pre>\n";
  if (!t.value("message", std::string()).empty()) {
    page += "<div class=\"message\">" + xmlEscaped(t.value("message", std::string())) + "</div>\n";
  }
  page += "</section>\n";
  for (const Json& record : member(t, "records", true)) {
    try {
      const SceneRecord r = recordFromJson(record, tableFile);
      page += "<section><h2>" + xmlEscaped(r.scene) + ": " + xmlEscaped(r.integrator) + ", step " + stepText(r) +
              "</h2>\n" + checkTable(r, ReportOptions{}) + "</section>\n";
    } catch (const Error&) {
      // A record of another version: shown as data below.
      page += "<section><pre>" + xmlEscaped(record.dump(2)) + "</pre></section>\n";
    }
  }
  char logName[32];
  std::snprintf(logName, sizeof logName, "logs/%04ld.log", index);
  if (fs::exists(from / logName)) {
    std::string log = readText(from / logName);
    if (log.size() > 200000) log = log.substr(0, 200000) + "\n[... cut at 200 kB]\n";
    page += "<section><h2>Log</h2><pre>" + xmlEscaped(log) + "</pre></section>\n";
  }
  page += "</main>\n</body>\n</html>\n";
  writeText(dir / taskPageName(index), page);
}

// Writes the plot of y against x (sweep.dat, sweep.gp, and sweep.svg by gnuplot); returns its
// section of the sweep's page, empty without a plot.
std::string writeSweepPlot(const fs::path& dir, const SweepLines& lines, const SweepAxes& a) {
  if (a.x.empty() || (lines[0].empty() && lines[1].empty())) return std::string();
  std::string dat, plots;
  int block = 0;
  for (int failedLine = 0; failedLine < 2; ++failedLine) {
    for (const auto& [s, points] : lines[failedLine]) {
      dat += points + "\n\n";
      const std::string title = (a.series.empty() ? std::string() : a.series + " = " + s) +
                                (failedLine ? std::string(a.series.empty() ? "" : ", ") + "failed" : "");
      plots += std::string(plots.empty() ? "" : ", ") + "'sweep.dat' index " + std::to_string(block++) +
               (failedLine ? " with points pt 2 ps 1.5 lc rgb '#a4161a'" : " with linespoints lw 2 pt 7") +
               " title " + gnuplotText(title.empty() ? a.y : title);
    }
  }
  writeText(dir / "sweep.dat", dat);
  std::string gp = std::string("# springy report: ") + a.y + " against " + a.x + "\n" + kSvgTerminal +
                   "set output 'sweep.svg'\nset xlabel " + gnuplotText(a.x) + "\nset ylabel " +
                   gnuplotText(a.y + (a.y.rfind("volume", 0) == 0 ? " (lowest body)" : " (largest body)")) +
                   "\nset title " + gnuplotText(a.y + " against " + a.x) + "\nplot " + plots + "\n";
  writeText(dir / "sweep.gp", gp);
  runGnuplot(dir / "sweep.gp");
  return "<section><h2>" + xmlEscaped(a.y) + " against " + xmlEscaped(a.x) + "</h2><img src=\"sweep.svg\" alt=\"" +
         xmlEscaped(a.y) + " against " + xmlEscaped(a.x) + "\" style=\"max-width:760px;width:100%\"><p class=\"files\">"
         "<a href=\"sweep.dat\">sweep.dat</a>, <a href=\"sweep.gp\">sweep.gp</a>; another figure: "
         "<code>springy report --sweep DIR --x KEY --y FIGURE</code></p></section>\n";
}

// Writes the sweep's page: its plot and the table of its tasks, a row each.
void writeSweepPage(const fs::path& dir, const fs::path& from, std::size_t tasks, int failed,
                    const std::vector<std::string>& keys, const std::string& plot, const std::string& rows) {
  std::string page = pageHead("springy sweep " + from.filename().string(), "../assets/");
  page += "<header><h1>Sweep " + xmlEscaped(from.filename().string()) + "</h1><p>" + std::to_string(tasks) +
          " tasks, " + std::to_string(failed) + " not ok &middot; <a href=\"../index.html\">all of the report</a>"
          "</p></header>\n<main>\n" + plot + "<section><h2>Tasks</h2>\n<table>\n<tr><th>task</th><th>scene</th>";
  for (const std::string& k : keys) page += "<th>" + xmlEscaped(k) + "</th>";
  page += "<th>status</th><th>volume min</th><th>max strain</th><th>max pen. [m]</th><th>steps</th><th>message</th>"
          "</tr>\n" + rows + "</table>\n</section>\n</main>\n</body>\n</html>\n";
  writeText(dir / "index.html", page);
}

// DIR/sweep/: a page per task and the sweep's page (a table and a plot); adds a link to the overview.
void reportSweep(const fs::path& root, const ReportOptions& o, std::string& overview) {
  const fs::path from(o.sweep);
  Json table = readSweepTable(from, o.sweep);
  const Json& tasks = table["tasks"];
  const SweepAxes axes = sweepAxes(tasks, o);
  const fs::path dir = root / "sweep";
  makeDirectories(dir.string(), "report");

  std::string rows;
  SweepLines lines;
  int failed = 0;
  for (const Json& t : tasks) {
    const long index = t.value("task", -1L);
    const std::string status = t.value("status", std::string("missing"));
    const bool ok = status == "ok";
    failed += ok ? 0 : 1;
    rows += taskRow(t, index, status, ok, axes.keys);
    addSweepPoint(lines[ok ? 0 : 1], t, axes);
    writeTaskPage(dir, from, (from / "table.json").string(), t, index, status, ok);
  }
  const std::string plot = writeSweepPlot(dir, lines, axes);
  writeSweepPage(dir, from, tasks.size(), failed, axes.keys, plot, rows);
  overview += "<section><h2>Sweep</h2><p><a href=\"sweep/index.html\">" + xmlEscaped(from.filename().string()) +
              "</a>: " + std::to_string(tasks.size()) + " tasks, " + std::to_string(failed) +
              " not ok</p></section>\n";
}

// ---- a study -------------------------------------------------------------------------------

// Markdown (GitHub's flavour: tables) as HTML, by cmark-gfm. A link to another page of the study
// (.md) goes to its .html; a link to anything the report does not hold (the repository's sources,
// a page outside the study) keeps its text and loses its target, so nothing in the report points
// at a file that is not there. `held(path)`: whether the report holds the study's file `path`.
template <typename Held>
std::string markdownHtml(const std::string& text, Held&& held) {
  cmark_gfm_core_extensions_ensure_registered();
  cmark_parser* parser = cmark_parser_new(CMARK_OPT_DEFAULT);
  for (const char* name : {"table", "autolink", "strikethrough"}) {
    if (cmark_syntax_extension* e = cmark_find_syntax_extension(name)) cmark_parser_attach_syntax_extension(parser, e);
  }
  cmark_parser_feed(parser, text.data(), text.size());
  cmark_node* doc = cmark_parser_finish(parser);
  std::vector<cmark_node*> unlinked;
  cmark_iter* it = cmark_iter_new(doc);
  for (cmark_event_type ev; (ev = cmark_iter_next(it)) != CMARK_EVENT_DONE;) {
    cmark_node* node = cmark_iter_get_node(it);
    const cmark_node_type type = cmark_node_get_type(node);
    if (ev != CMARK_EVENT_ENTER || (type != CMARK_NODE_LINK && type != CMARK_NODE_IMAGE)) continue;
    std::string url = cmark_node_get_url(node) ? cmark_node_get_url(node) : "";
    if (url.empty() || url[0] == '#' || url.find("://") != std::string::npos) continue;
    const std::size_t hash = url.find('#');
    const std::string file = url.substr(0, hash), anchor = hash == std::string::npos ? "" : url.substr(hash);
    if (file.size() > 3 && file.compare(file.size() - 3, 3, ".md") == 0 && held(file)) {
      cmark_node_set_url(node, (file.substr(0, file.size() - 3) + ".html" + anchor).c_str());
    } else if (!held(file) && type == CMARK_NODE_LINK) {
      unlinked.push_back(node);
    }
  }
  cmark_iter_free(it);
  for (cmark_node* link : unlinked) {
    while (cmark_node* child = cmark_node_first_child(link)) cmark_node_insert_before(link, child);
    cmark_node_free(link);
  }
  char* html = cmark_render_html(doc, CMARK_OPT_DEFAULT, cmark_parser_get_syntax_extensions(parser));
  std::string out(html);
  std::free(html);
  cmark_node_free(doc);
  cmark_parser_free(parser);
  return out;
}

void reportStudy(const fs::path& root, const ReportOptions& o, std::string& overview) {
  const fs::path from(o.study);
  std::vector<fs::path> pages;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(from, ec)) {
    if (e.path().extension() == ".md") pages.push_back(e.path());
  }
  if (ec) throw Error("--study " + o.study + ": cannot read the folder: " + ec.message());
  if (pages.empty()) {
    throw Error("--study " + o.study + ": no study's pages (.md) there; `springy study accuracy -o " + o.study +
                "` writes them");
  }
  std::sort(pages.begin(), pages.end());
  const fs::path dir = root / "study";
  makeDirectories(dir.string(), "report");
  overview += "<section><h2>Study</h2><ul>";
  for (const fs::path& md : pages) {
    const std::string text = readText(md);
    // The plots and tables the page names come along.
    for (const fs::directory_entry& e : fs::directory_iterator(from)) {
      const std::string name = e.path().filename().string();
      const std::string ext = e.path().extension().string();
      if ((ext == ".png" || ext == ".svg" || ext == ".csv" || ext == ".dat" || ext == ".gp") &&
          text.find(name) != std::string::npos && !fs::exists(dir / name)) {
        copyFile(e.path(), dir / name);
      }
    }
  }
  const auto held = [&](const std::string& file) {
    if (file.find('/') != std::string::npos) return false;  // the study's pages and files sit side by side
    if (file.size() > 3 && file.compare(file.size() - 3, 3, ".md") == 0) return fs::exists(from / file);
    return fs::exists(dir / file);
  };
  for (const fs::path& md : pages) {
    const std::string text = readText(md);
    const std::string name = md.stem().string();
    std::string page = pageHead("springy study: " + name, "../assets/");
    page += "<header><h1>" + xmlEscaped(name) + "</h1><p>" + xmlEscaped(md.string()) +
            " &middot; <a href=\"../index.html\">all of the report</a></p></header>\n<main><section class=\"study\">\n" +
            markdownHtml(text, held) + "</section></main>\n</body>\n</html>\n";
    writeText(dir / (name + ".html"), page);
    overview += "<li><a href=\"study/" + urlPath(name) + ".html\">" + xmlEscaped(name) + "</a></li>";
  }
  overview += "</ul></section>\n";
}

}  // namespace

int runReport(const ReportOptions& o) {
  if (o.scenes.empty() && o.sweep.empty() && o.study.empty()) {
    throw Error("report: give scenes, --sweep DIR or --study DIR");
  }
  if (!haveGnuplot()) throw Error("report: gnuplot is not installed (its plots need it): apt install gnuplot-nox");
  // Each scene gets its folder, named by its file.
  std::vector<SceneResult> scenes;
  for (const std::string& path : o.scenes) {
    SceneResult& s = scenes.emplace_back();
    s.path = path;
    s.stem = fs::path(path).stem().string();
    if (s.stem == "assets" || s.stem == "sweep" || s.stem == "study") s.stem += "-scene";
    for (std::size_t j = 0; j + 1 < scenes.size(); ++j) {
      if (scenes[j].stem == s.stem) throw Error("report: " + scenes[j].path + " and " + path + " share the name " + s.stem);
    }
  }
  // What the report reads (the scenes' files, the sweep's and study's folders) must not be in the
  // folder it replaces.
  std::vector<std::string> inputs = sceneInputFiles(o.scenes, o.run.sets);
  for (const std::string& folder : {o.sweep, o.study}) {
    if (!folder.empty()) inputs.push_back(folder);
  }
  OutputFolder out(o.output, kMarker, "springy report: this folder is replaced by the next report written to it\n",
                   "-o " + o.output, inputs);
  const fs::path root(out.temporaryPath());
  makeDirectories((root / "assets").string(), "report");
  writeText(root / "assets" / "viewer.js",
            std::string(springy_report_viewer, static_cast<std::size_t>(springy_report_viewer_end - springy_report_viewer)));
  writeText(root / "assets" / "report.css",
            std::string(springy_report_style, static_cast<std::size_t>(springy_report_style_end - springy_report_style)));

  int status = 0;
  std::string rows;
  for (SceneResult& s : scenes) {
    if (!reportScene(root, s, o)) {
      std::cerr << "springy report: interrupted\n";
      return interruptedExitStatus();
    }
    const SceneRecord& r = s.record;
    const bool ok = r.status == SceneRecord::Status::Ok;
    status = ok ? status : 1;
    double volumeMin = std::numeric_limits<double>::infinity(), strain = 0.0;
    for (const BodyResult& b : r.bodies) {
      if (b.volumeMin) volumeMin = std::min(volumeMin, *b.volumeMin);
      strain = std::max(strain, b.maxStrain);
    }
    rows += "<tr><td><a href=\"" + urlPath(s.stem) + "/index.html\">" + xmlEscaped(r.scene.empty() ? s.stem : r.scene) +
            "</a></td><td class=\"" + (ok ? "ok" : "bad") + "\">" + statusName(r.status) + "</td><td>" +
            xmlEscaped(r.integrator) + "</td><td>" + stepText(r) + "</td><td>" + number(r.duration) + " s</td><td>" +
            std::to_string(r.bodies.size()) + "</td><td>" + number(volumeMin, "%.3f") + "</td><td>" + number(strain) +
            "</td><td>" + number(r.wall, "%.3g") + " s</td><td>" +
            (s.motion ? "<a href=\"" + urlPath(s.stem) + "/index.html\"><img class=\"thumb\" src=\"" +
                            urlPath(s.stem + "/" + s.stem + "_sheet.png") + "\" alt=\"contact sheet\"></a>"
                      : std::string("-")) +
            "</td></tr>\n";
  }
  std::string extra;
  if (!o.sweep.empty()) reportSweep(root, o, extra);
  if (!o.study.empty()) reportStudy(root, o, extra);

  std::string page = pageHead("springy report", "assets/");
  page += "<header><h1>springy report</h1><p>";
  for (const std::string& a : o.command) page += xmlEscaped(a) + " ";
  page += "</p></header>\n<main>\n";
  if (!scenes.empty()) {
    page += "<section><h2>Scenes</h2>\n<table>\n<tr><th>scene</th><th>result</th><th>integrator</th><th>step</th>"
            "<th>simulated</th><th>bodies</th><th>volume min</th><th>max strain</th><th>wall</th><th>contact sheet"
            "</th></tr>\n" + rows + "</table>\n<p class=\"files\">Criteria: " + criteriaText(o) + ".</p></section>\n";
  }
  page += extra + "</main>\n</body>\n</html>\n";
  writeText(root / "index.html", page);
  out.commit();
  std::printf("report: wrote %s/index.html\n", out.target().c_str());
  return status;
}

}  // namespace springy
