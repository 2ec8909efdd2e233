// springy export and check --export (issue 42), the command-line side: the same bytes on any
// thread count, memory that does not grow with the run's frames, outputs that appear complete or
// not at all (a full disk, Ctrl-C, a failed run), and clear errors for a bad extension or an
// unwritable place. What other programs read in the files is tests/export_roundtrip.sh's part.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "springy_process.h"

namespace {

namespace fs = std::filesystem;
using springy::test::Clock;
using springy::test::Result;
using springy::test::Springy;

const std::string kScene = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/export/roundtrip.toml";
const std::string kThreads = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/export/threads.toml";
const std::string kUnstable = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/app/unstable.toml";
// The scene's drawn vertices: two icospheres of 42 and the bunny's own 1839 (scenes/assets/bunny.ply).
constexpr int32_t kDrawnVertices = 42 + 42 + 1839;

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

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
