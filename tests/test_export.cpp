// springy export and check --export (issue 42), the command-line side: the same bytes on any
// thread count, memory that does not grow with the run's frames, outputs that appear complete or
// not at all (a full disk, Ctrl-C, a failed run), and clear errors for a bad extension or an
// unwritable place; a collider that moves (issue 58) where its motion has it in every format, read
// back here (.glb, .pvd and its .vtu, .pc2) against sim/motion.h. What other programs read in the
// files is tests/export_roundtrip.sh's part.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "springy_process.h"

namespace {

namespace fs = std::filesystem;
using springy::test::Clock;
using springy::test::Result;
using springy::test::Springy;

const std::string kScene = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/export/roundtrip.toml";
const std::string kThreads = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/export/threads.toml";
const std::string kUnstable = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/app/unstable.toml";
// A plate (triangle collider 0) that comes down on a ball from 0.3 s to 1.5 s and holds to 2.2 s.
const std::string kPress = std::string(SPRINGY_SOURCE_DIR) + "/scenes/press.toml";
// The scene's drawn vertices: two icospheres of 42 and the bunny's own 1839 (scenes/assets/bunny.ply).
constexpr int32_t kDrawnVertices = 42 + 42 + 1839;

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// A .glb read back: its JSON chunk and its binary chunk.
struct Glb {
  nlohmann::json doc;
  std::string bin;
  // Accessor `a`'s floats, through its buffer view.
  std::vector<float> floats(std::size_t a) const {
    const nlohmann::json& accessor = doc["accessors"][a];
    const nlohmann::json& view = doc["bufferViews"][accessor["bufferView"].get<std::size_t>()];
    const std::string type = accessor["type"];
    const std::size_t components = type == "SCALAR" ? 1 : type == "VEC3" ? 3 : 4;
    std::vector<float> out(accessor["count"].get<std::size_t>() * components);
    const std::size_t at = view["byteOffset"].get<std::size_t>() + accessor.value("byteOffset", std::size_t{0});
    EXPECT_LE(at + 4 * out.size(), bin.size());
    if (at + 4 * out.size() <= bin.size()) std::memcpy(out.data(), bin.data() + at, 4 * out.size());
    return out;
  }
  std::size_t node(const std::string& name) const {
    for (std::size_t n = 0; n < doc["nodes"].size(); ++n) {
      if (doc["nodes"][n]["name"] == name) return n;
    }
    ADD_FAILURE() << "no node " << name;
    return 0;
  }
};
Glb readGlb(const fs::path& path) {
  const std::string bytes = readFile(path);
  Glb g;
  uint32_t length = 0;
  if (bytes.size() < 28 || bytes.compare(0, 4, "glTF") != 0) return ADD_FAILURE() << path << " is no GLB", g;
  std::memcpy(&length, bytes.data() + 12, 4);
  g.doc = nlohmann::json::parse(bytes.substr(20, length));
  const std::size_t bin = 20 + length;
  std::memcpy(&length, bytes.data() + bin, 4);
  g.bin = bytes.substr(bin + 8, length);
  return g;
}

// A .pvd's data sets: time, group, part, name, file.
struct DataSet {
  double time;
  std::string group, part, name, file;
};
std::vector<DataSet> readPvd(const fs::path& path) {
  const std::string text = readFile(path);
  const std::regex item(R"re(<DataSet timestep="([^"]*)" group="([^"]*)" part="([^"]*)" name="([^"]*)" file="([^"]*)"/>)re");
  std::vector<DataSet> out;
  for (auto m = std::sregex_iterator(text.begin(), text.end(), item); m != std::sregex_iterator(); ++m) {
    out.push_back({std::stod((*m)[1]), (*m)[2], (*m)[3], (*m)[4], (*m)[5]});
  }
  return out;
}

// The points of a .vtu springy wrote (appended raw, UInt64 headers, Float64 positions).
std::vector<springy::Vec3> vtuPoints(const fs::path& path) {
  const std::string text = readFile(path);
  std::smatch m;
  const std::regex position(R"re(Name="position" NumberOfComponents="3" format="appended" offset="(\d+)")re");
  const std::string mark = "<AppendedData encoding=\"raw\">\n_";
  if (!std::regex_search(text, m, position) || !contains(text, mark)) return ADD_FAILURE() << path, std::vector<springy::Vec3>{};
  const std::size_t at = text.find(mark) + mark.size() + std::stoull(m[1]);
  uint64_t bytes = 0;
  std::memcpy(&bytes, text.data() + at, 8);
  std::vector<springy::Vec3> out(bytes / 24);
  for (std::size_t k = 0; k < out.size(); ++k) std::memcpy(&out[k].x, text.data() + at + 8 + 24 * k, 24);
  return out;
}

// Sample k of a .pc2 file: its points.
std::vector<springy::Vec3> pc2Sample(const fs::path& path, int32_t k) {
  const std::string cache = readFile(path);
  int32_t points = 0, samples = 0;
  std::memcpy(&points, cache.data() + 16, 4);
  std::memcpy(&samples, cache.data() + 28, 4);
  EXPECT_LT(k, samples) << path;
  EXPECT_EQ(cache.size(), 32u + 12u * static_cast<std::size_t>(points) * static_cast<std::size_t>(samples)) << path;
  std::vector<springy::Vec3> out(static_cast<std::size_t>(points));
  for (std::size_t i = 0; i < out.size(); ++i) {
    float p[3];
    std::memcpy(p, cache.data() + 32 + 12 * (static_cast<std::size_t>(k) * out.size() + i), 12);
    out[i] = {p[0], p[1], p[2]};
  }
  return out;
}

class ExportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() / ("springy_export_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static Result run(const std::vector<std::string>& args, Springy::Options options = {}, double timeout = 120.0) {
    Springy s(args, options);
    return s.wait(timeout);
  }
  // Every path under `d` (hidden ones too), sorted.
  std::vector<std::string> listing(const fs::path& d) const {
    std::vector<std::string> n;
    for (const auto& e : fs::recursive_directory_iterator(d)) n.push_back(fs::relative(e.path(), d).string());
    std::sort(n.begin(), n.end());
    return n;
  }
  std::string listingText(const fs::path& d) const {
    std::string s;
    for (const std::string& n : listing(d)) s += n + " ";
    return "[" + s + "]";
  }
  // The bytes of an export: the file and what is written beside it.
  std::string exported(const fs::path& out) const {
    std::string all;
    const std::string ext = out.extension().string();
    std::vector<fs::path> files{out};
    if (ext == ".pc2") files.insert(files.end(), {fs::path(out).replace_extension(".obj"), fs::path(out).replace_extension(".mtl")});
    if (ext == ".pvd") {
      std::vector<fs::path> frames;
      for (const auto& e : fs::directory_iterator(fs::path(out).replace_extension(""))) frames.push_back(e.path());
      std::sort(frames.begin(), frames.end());
      files.insert(files.end(), frames.begin(), frames.end());
    }
    for (const fs::path& f : files) all += f.filename().string() + "\n" + readFile(f);
    return all;
  }

  fs::path dir_;
};

const std::vector<std::string> kFormats{"pc2", "glb", "pvd"};

TEST_F(ExportTest, WritesTheSameBytesOnOneAndTwoThreads) {
  for (const std::string& format : kFormats) {
    std::string bytes[2];
    for (int threads = 1; threads <= 2; ++threads) {
      const fs::path out = dir_ / std::to_string(threads) / ("run." + format);
      fs::create_directories(out.parent_path());
      const Result r = run({"export", kThreads, "-o", out.string(), "--threads", std::to_string(threads)});
      ASSERT_EQ(r.status, 0) << r.output;
      EXPECT_TRUE(contains(r.output, "threads: " + std::to_string(threads))) << r.output;
      bytes[threads - 1] = exported(out);
    }
    EXPECT_GT(bytes[0].size(), 10000u) << format;
    EXPECT_TRUE(bytes[0] == bytes[1]) << format << ": the exports on 1 and 2 threads differ";
  }
}

TEST_F(ExportTest, ThePointCacheHoldsEveryFrameOfTheDrawnMeshes) {
  // The bunny is simulated through a proxy: the cache holds the user's 1839 vertices, not the
  // proxy's; 15 frames of 0.5 s at 30 per second and the first instant.
  const fs::path out = dir_ / "run.pc2";
  const Result r = run({"export", kScene, "-o", out.string(), "--duration", "0.5"});
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "30/30 frames") || contains(r.output, "15/15 frames")) << r.output;
  const std::string cache = readFile(out);
  ASSERT_GE(cache.size(), 32u);
  int32_t points = 0, samples = 0;
  std::memcpy(&points, cache.data() + 16, 4);
  std::memcpy(&samples, cache.data() + 28, 4);
  EXPECT_EQ(std::string(cache.data(), 11), "POINTCACHE2");
  EXPECT_EQ(points, kDrawnVertices);
  EXPECT_EQ(samples, 16);
  EXPECT_EQ(cache.size(), 32u + 16u * static_cast<std::size_t>(kDrawnVertices) * 12u);
  // The OBJ beside it: as many vertices, one object.
  const std::string obj = readFile(fs::path(out).replace_extension(".obj"));
  std::size_t vertices = 0;
  for (std::size_t at = obj.find("\nv "); at != std::string::npos; at = obj.find("\nv ", at + 1)) ++vertices;
  EXPECT_EQ(vertices, static_cast<std::size_t>(kDrawnVertices));
  EXPECT_TRUE(contains(r.output, "exported: " + out.string())) << r.output;
}

// The press's plate, 2 s of it at 30 frames a second: each format carries its pose at every frame,
// at the frame's simulated time (the .pvd's times: the step nearest to k / 30), as the scene's
// motion gives it.
class MovingExportTest : public ExportTest {
 protected:
  void SetUp() override {
    ExportTest::SetUp();
    for (const std::string& format : kFormats) {
      const Result r = run({"export", kPress, "-o", (dir_ / ("press." + format)).string(), "--duration", "2"});
      ASSERT_EQ(r.status, 0) << r.output;
      output_ += r.output;
    }
    for (const DataSet& d : readPvd(dir_ / "press.pvd")) {
      if (d.group == "colliders") plate_.push_back(d);
    }
    ASSERT_EQ(plate_.size(), kFrames) << "the plate's series in press.pvd";
  }
  // Where the plate's motion has its vertex p at frame k, and the node's translation then.
  springy::Vec3 placed(const springy::Vec3& p, std::size_t k) const { return motion().pose(plate_[k].time).apply(p); }
  const springy::Movement& motion() const { return scene_.triangleColliders[0].motion; }
  void checkGlb();
  void checkPvd();
  void checkPc2();

  static constexpr std::size_t kFrames = 61;
  // The first, two on the way down, one held at the bottom (1.5-2.2 s), the last.
  const std::vector<std::size_t> frames_{0, 15, 30, 45, 60};
  const springy::SceneDesc scene_ = springy::loadScene(kPress);
  std::vector<DataSet> plate_;
  std::string output_;
};

void MovingExportTest::checkGlb() {
  const Glb g = readGlb(dir_ / "press.glb");
  const std::size_t node = g.node("collider 0");
  std::optional<std::size_t> sampler;
  const nlohmann::json& animation = g.doc["animations"][0];
  for (const nlohmann::json& c : animation["channels"]) {
    if (c["target"]["node"] == node) {
      EXPECT_EQ(c["target"]["path"], "translation") << "the plate only moves: no rotation";
      sampler = c["sampler"].get<std::size_t>();
    }
  }
  ASSERT_TRUE(sampler) << "no channel animates the plate's node";
  const nlohmann::json& s = animation["samplers"][*sampler];
  EXPECT_EQ(s["interpolation"], "LINEAR");
  const std::vector<float> times = g.floats(s["input"]), translation = g.floats(s["output"]);
  ASSERT_EQ(times.size(), kFrames);
  ASSERT_EQ(translation.size(), 3 * kFrames);
  for (std::size_t k : frames_) {
    EXPECT_FLOAT_EQ(times[k], static_cast<float>(static_cast<double>(k) / 30.0));
    const springy::Vec3 expected = placed({0, 0, 0}, k);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(translation[3 * k + c], expected[c], 1e-6) << "frame " << k << " at " << plate_[k].time << " s";
    }
  }
  EXPECT_NEAR(translation[3 * 45 + 1], -0.7, 1e-6) << "held at the bottom";
  EXPECT_NEAR(translation[3 * 15 + 1], motion().translation(plate_[15].time).y, 1e-6);
  EXPECT_LT(translation[3 * 15 + 1], -0.01) << "on its way down at 0.5 s";
  // The node stands at the first frame's pose; its mesh is the plate at rest; nothing else moves.
  EXPECT_EQ(g.doc["nodes"][node]["translation"], nlohmann::json::array({0.0, 0.0, 0.0}));
  const std::vector<float> rest = g.floats(g.doc["meshes"][g.doc["nodes"][node]["mesh"].get<std::size_t>()]["primitives"][0]["attributes"]["POSITION"]);
  ASSERT_EQ(rest.size(), 3 * scene_.triangleColliders[0].mesh.positions.size());
  EXPECT_FLOAT_EQ(rest[1], 1.2f);
  for (const std::string name : {"ball", "plane 0"}) EXPECT_FALSE(g.doc["nodes"][g.node(name)].contains("translation")) << name;
}

void MovingExportTest::checkPvd() {
  const std::vector<springy::Vec3>& rest = scene_.triangleColliders[0].mesh.positions;
  std::size_t bodies = 0;
  for (const DataSet& d : readPvd(dir_ / "press.pvd")) bodies += d.group.empty();
  EXPECT_EQ(bodies, kFrames) << "the ball's series";
  for (std::size_t k : frames_) {
    const DataSet& d = plate_[k];
    EXPECT_EQ(d.name, "collider 0");
    EXPECT_EQ(d.part, "1");
    EXPECT_EQ(d.file, "press/collider0_" + std::string(6 - std::to_string(k).size(), '0') + std::to_string(k) + ".vtu");
    EXPECT_NEAR(d.time, static_cast<double>(k) / 30.0, 0.5 / 30.0);
    const std::vector<springy::Vec3> points = vtuPoints(dir_ / d.file);
    ASSERT_EQ(points.size(), rest.size()) << d.file;
    for (std::size_t i = 0; i < rest.size(); ++i) {
      EXPECT_LT(length(points[i] - placed(rest[i], k)), 1e-12) << d.file << " point " << i;
    }
    EXPECT_NEAR(points[0].y - rest[0].y, motion().translation(d.time).y, 1e-12) << d.file;
  }
  EXPECT_NEAR(vtuPoints(dir_ / plate_[45].file)[0].y, 0.5, 1e-12) << "the plate's underside at the bottom";
}

void MovingExportTest::checkPc2() {
  const std::vector<springy::Vec3>& rest = scene_.triangleColliders[0].mesh.positions;
  const fs::path cache = dir_ / "press.collider0.pc2";
  ASSERT_TRUE(fs::exists(cache)) << listingText(dir_);
  for (std::size_t k : frames_) {
    const std::vector<springy::Vec3> points = pc2Sample(cache, static_cast<int32_t>(k));
    ASSERT_EQ(points.size(), rest.size());
    for (std::size_t i = 0; i < rest.size(); ++i) {
      EXPECT_LT(length(points[i] - placed(rest[i], k)), 1e-6) << "frame " << k << " point " << i;
    }
  }
  // The body's cache is as before: the ball's 642 points; the OBJ has the plate as an object.
  EXPECT_EQ(pc2Sample(dir_ / "press.pc2", 0).size(), 642u);
  const std::string obj = readFile(dir_ / "press.obj");
  EXPECT_TRUE(contains(obj, "\no springy\n") && contains(obj, "\no collider0\n")) << obj.substr(0, 400);
  EXPECT_TRUE(contains(readFile(dir_ / "press.mtl"), "newmtl collider0\n"));
  EXPECT_TRUE(contains(output_, "press.obj, " + cache.string() + " and ")) << output_;
}

TEST_F(MovingExportTest, ThePressPlateMovesInEveryFormat) {
  {
    SCOPED_TRACE("press.glb");
    checkGlb();
  }
  {
    SCOPED_TRACE("press.pvd");
    checkPvd();
  }
  {
    SCOPED_TRACE("press.pc2");
    checkPc2();
  }
}

TEST_F(ExportTest, AStillSceneHasNoPoses) {
  // Nothing moves in the round trip's scene: no node placed, no collider series, no other cache.
  for (const std::string& format : kFormats) {
    const Result r = run({"export", kScene, "-o", (dir_ / ("run." + format)).string(), "--duration", "0.2"});
    ASSERT_EQ(r.status, 0) << r.output;
  }
  const Glb g = readGlb(dir_ / "run.glb");
  for (const nlohmann::json& n : g.doc["nodes"]) EXPECT_FALSE(n.contains("translation")) << n.dump();
  for (const nlohmann::json& c : g.doc["animations"][0]["channels"]) EXPECT_EQ(c["target"]["path"], "weights");
  for (const DataSet& d : readPvd(dir_ / "run.pvd")) EXPECT_EQ(d.group, "") << d.file;
  std::size_t caches = 0;
  for (const auto& e : fs::directory_iterator(dir_)) caches += e.path().extension() == ".pc2";
  EXPECT_EQ(caches, 1u) << listingText(dir_);
}

TEST_F(ExportTest, MemoryDoesNotGrowWithTheFrames) {
  // 60 and 600 frames of the same run (0.25 and 2.5 s at 240 per second): the longer export is ten
  // times the bytes, tens of MB, while the process's peak memory grows by a small part of that
  // (glTF's JSON, a few hundred bytes a frame and body, is the one thing kept to the end).
  for (const std::string& format : kFormats) {
    long rss[2] = {0, 0};
    uintmax_t size[2] = {0, 0};
    const char* durations[2] = {"0.25", "2.5"};
    for (int i = 0; i < 2; ++i) {
      const fs::path out = dir_ / std::to_string(i) / ("run." + format);
      fs::create_directories(out.parent_path());
      const Result r = run({"export", kScene, "-o", out.string(), "--fps", "240", "--duration", durations[i]});
      ASSERT_EQ(r.status, 0) << r.output;
      rss[i] = r.maxRssKiB;
      for (const auto& e : fs::recursive_directory_iterator(out.parent_path())) {
        if (e.is_regular_file()) size[i] += e.file_size();
      }
    }
    const double grown = static_cast<double>(size[1] - size[0]) / 1024.0;  // KiB
    EXPECT_GT(grown, 10000.0) << format;
    EXPECT_LT(static_cast<double>(rss[1] - rss[0]), 0.1 * grown)
        << format << ": peak memory " << rss[0] << " KiB for 60 frames, " << rss[1] << " KiB for 600 ("
        << grown << " KiB more output)";
  }
}

TEST_F(ExportTest, AFullDiskLeavesNoFile) {
  // RLIMIT_FSIZE: a write past 64 KiB fails with EFBIG, as on a full disk (a bunny frame is 22-44
  // KiB). The export fails, says so, and leaves nothing: no output, no temporary file or folder.
  for (const std::string& format : kFormats) {
    const fs::path out = dir_ / ("run." + format);
    Springy::Options options;
    options.fileSizeLimit = 64 * 1024;
    options.ignoreXfsz = true;
    const Result r = run({"export", kScene, "-o", out.string(), "--duration", "0.5"}, options);
    EXPECT_NE(r.status, 0) << format << ": " << r.output;
    EXPECT_TRUE(contains(r.output, "File too large")) << format << ": " << r.output;
    EXPECT_TRUE(listing(dir_).empty()) << format << " left " << listingText(dir_);
  }
}

TEST_F(ExportTest, CtrlCLeavesNoFile) {
  for (const std::string& format : kFormats) {
    const fs::path out = dir_ / ("run." + format);
    Springy s({"export", kScene, "-o", out.string(), "--duration", "60"}, {});
    // Interrupted mid-run: once its temporary output exists, and half a second of frames later.
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    while (listing(dir_).empty() && Clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_FALSE(listing(dir_).empty()) << format << ": no temporary output appeared";
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    s.signal(SIGINT);
    const Result r = s.wait(60.0);
    EXPECT_EQ(r.status, 128 + SIGINT) << format << ": " << r.output;
    EXPECT_TRUE(contains(r.output, "interrupted")) << format << ": " << r.output;
    EXPECT_TRUE(listing(dir_).empty()) << format << " left " << listingText(dir_);
  }
}

TEST_F(ExportTest, AFailedRunIsNotExported) {
  const fs::path out = dir_ / "unstable.glb";
  const Result r = run({"export", kUnstable, "-o", out.string()});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "not exported: the run failed")) << r.output;
  EXPECT_TRUE(listing(dir_).empty()) << listingText(dir_);
}

TEST_F(ExportTest, ABadExtensionIsAClearErrorBeforeTheRun) {
  struct Case {
    std::string name, says;
  };
  for (const Case& c : {Case{"run.usda", "USD is not written"}, Case{"run.gltf", "one binary file: .glb"},
                        Case{"run.vtu", "a time series: .pvd"}, Case{"run.mp4", "'.mp4' is not a format"},
                        Case{"run", "has no extension"}}) {
    const Result r = run({"export", kScene, "-o", (dir_ / c.name).string()});
    EXPECT_EQ(r.status, 1) << c.name << ": " << r.output;
    EXPECT_TRUE(contains(r.output, c.says)) << c.name << ": " << r.output;
    EXPECT_TRUE(contains(r.output, ".pc2") && contains(r.output, ".glb") && contains(r.output, ".pvd")) << r.output;
    EXPECT_FALSE(contains(r.output, "steps")) << c.name << ": ran before failing: " << r.output;
    EXPECT_TRUE(listing(dir_).empty()) << listingText(dir_);
  }
}

TEST_F(ExportTest, AnUnwritablePlaceIsAClearErrorBeforeTheRun) {
  for (const std::string& format : kFormats) {
    const std::string out = (dir_ / "missing" / ("run." + format)).string();
    const Result r = run({"export", kScene, "-o", out});
    EXPECT_NE(r.status, 0) << r.output;
    EXPECT_TRUE(contains(r.output, dir_.string() + "/missing")) << format << ": " << r.output;
    EXPECT_FALSE(contains(r.output, "frames (")) << format << ": ran before failing: " << r.output;
  }
  // The series' folder exists and is the user's: it is not replaced.
  fs::create_directories(dir_ / "run");
  std::ofstream(dir_ / "run" / "notes.txt") << "mine";
  const Result r = run({"export", kScene, "-o", (dir_ / "run.pvd").string()});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "was not written by springy")) << r.output;
  EXPECT_EQ(readFile(dir_ / "run" / "notes.txt"), "mine");
  EXPECT_FALSE(fs::exists(dir_ / "run.pvd"));
}

TEST_F(ExportTest, ASecondExportReplacesTheFirstsSeries) {
  // Exported twice, the second time shorter: the folder holds the second run's frames only.
  const fs::path out = dir_ / "run.pvd";
  ASSERT_EQ(run({"export", kScene, "-o", out.string(), "--duration", "0.5"}).status, 0);
  ASSERT_EQ(run({"export", kScene, "-o", out.string(), "--duration", "0.2"}).status, 0);
  std::size_t vtu = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "run")) vtu += e.path().extension() == ".vtu";
  EXPECT_EQ(vtu, 3u * 7u) << listingText(dir_);  // 3 bodies, 6 frames and the first instant
  EXPECT_EQ(listing(dir_).size(), 2u + 1u + vtu) << listingText(dir_);  // run.pvd, run/, its marker
}

TEST_F(ExportTest, CheckExportsEachSceneIntoADirectory) {
  const fs::path scenes = dir_ / "scenes";
  fs::create_directories(scenes);
  fs::copy_file(kScene, scenes / "one.toml");
  fs::copy_file(kScene, scenes / "two.toml");
  // The copies name the bunny's mesh relative to the scene: give it from here.
  for (const char* name : {"one.toml", "two.toml"}) {
    std::string text = readFile(scenes / name);
    const std::string from = "\"../../../scenes/assets/bunny.ply\"";
    text.replace(text.find(from), from.size(), "\"" + std::string(SPRINGY_SOURCE_DIR) + "/scenes/assets/bunny.ply\"");
    std::ofstream(scenes / name) << text;
  }
  const fs::path out = dir_ / "out";
  const Result r = run({"check", (scenes / "one.toml").string(), (scenes / "two.toml").string(), "--duration", "0.2",
                        "--export", out.string(), "--export-format", "glb"});
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(exported(out / "one.glb").substr(8), exported(out / "two.glb").substr(8));
  EXPECT_TRUE(contains(r.output, "exported: " + (out / "one.glb").string())) << r.output;
}

}  // namespace
