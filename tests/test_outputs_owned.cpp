// Nothing a user owns is lost (issue 63): no springy command replaces a file it did not write.
// Every file a scene reads (the scene, its meshes, an OBJ's .mtl and textures) is an input that no
// output replaces; the files an export names by itself (a point cache's .obj and .mtl, the
// series' folder, -o DIR's SCENE.EXT) replace only springy's own; a folder springy replaces (a
// report, a series) keeps what the user added, the command refusing before it runs; a failed or
// interrupted run leaves no temporary file and the earlier outputs as they were. Each test runs
// the real binary and checks the bytes of every file it must not touch, the message and the
// exit status.
#include <gtest/gtest.h>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "springy_process.h"
#include "test_folder.h"

namespace {

namespace fs = std::filesystem;
using springy::test::Clock;
using springy::test::Result;
using springy::test::Springy;

using springy::test::readFile;
using springy::test::writeFile;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// An icosahedron as a user's OBJ, with a material library that names a texture.
const std::string kIcosahedron =
    "# a user's mesh\nmtllib MTL\no ico\n"
    "v 0 1 1.618\nv 0 -1 1.618\nv 0 1 -1.618\nv 0 -1 -1.618\nv 1 1.618 0\nv -1 1.618 0\n"
    "v 1 -1.618 0\nv -1 -1.618 0\nv 1.618 0 1\nv 1.618 0 -1\nv -1.618 0 1\nv -1.618 0 -1\nusemtl red\n"
    "f 1 2 9\nf 1 9 5\nf 1 5 6\nf 1 6 11\nf 1 11 2\nf 2 11 8\nf 2 8 7\nf 2 7 9\nf 9 7 10\nf 9 10 5\n"
    "f 5 10 3\nf 5 3 6\nf 6 3 12\nf 6 12 11\nf 11 12 8\nf 4 3 10\nf 4 10 7\nf 4 7 8\nf 4 8 12\nf 4 12 3\n";

class OwnedOutputs : public springy::test::FolderTest {
 protected:
  OwnedOutputs() : FolderTest("owned") {}

  // A scene `stem`.toml whose body is the mesh `mesh` (an icosahedron OBJ whose mtllib is `mtl`,
  // which names the texture `texture`), above a ground; `extra` goes in [scene].
  fs::path meshScene(const std::string& stem, const std::string& mesh, const std::string& mtl = "teapot.mtl",
                     const std::string& texture = "teapot.png", const std::string& extra = "") {
    std::string obj = kIcosahedron;
    obj.replace(obj.find("MTL"), 3, mtl);
    writeFile(dir_ / mesh, obj);
    writeFile(dir_ / mtl, "newmtl red\nKd 1 0 0\nmap_Kd " + texture + "\n");
    writeFile(dir_ / texture, "\x89PNG a user's texture");
    const fs::path scene = dir_ / (stem + ".toml");
    writeFile(scene, "[scene]\nduration = 0.2\n" + extra + "\n[[body]]\nname = \"teapot\"\nshape = \"mesh\"\nmesh = \"" +
                         mesh + "\"\nposition = [0, 3, 0]\n\n[[plane]]\n");
    return scene;
  }
  // Every file under the test's folder and its bytes.
  std::map<std::string, std::string> snapshot() const {
    std::map<std::string, std::string> out;
    for (const auto& e : fs::recursive_directory_iterator(dir_)) {
      if (e.is_regular_file()) out[e.path().lexically_relative(dir_).string()] = readFile(e.path());
    }
    return out;
  }
  // What differs from `before`: the files changed, made or removed since ("" when none).
  std::string changesSince(const std::map<std::string, std::string>& before) const {
    const auto now = snapshot();
    std::string out;
    for (const auto& [file, bytes] : before) {
      const auto it = now.find(file);
      if (it == now.end()) out += "removed " + file + "; ";
      else if (it->second != bytes) out += "changed " + file + "; ";
    }
    for (const auto& [file, bytes] : now) {
      if (!before.count(file)) out += "made " + file + "; ";
    }
    return out;
  }
  // A copy of tests/data/app/tiny.toml (a small ball that comes to rest on a ground) as `name`.
  std::string tiny(const std::string& name) const {
    fs::copy_file(std::string(SPRINGY_SOURCE_DIR) + "/tests/data/app/tiny.toml", dir_ / name);
    return (dir_ / name).string();
  }
  // The names under the test's folder that are temporary files or folders.
  std::vector<std::string> temporaries() const {
    std::vector<std::string> out;
    for (const auto& e : fs::recursive_directory_iterator(dir_)) {
      const std::string name = e.path().filename().string();
      if (contains(name, ".tmp-") || contains(name, ".springy-spill")) out.push_back(e.path().string());
    }
    return out;
  }
  Result run(const std::vector<std::string>& args) {
    Springy s(args, {});
    return s.wait(120.0);
  }
  // Waits until a temporary file or folder appears under the test's folder.
  bool waitForTemporary(double timeout = 30.0) const {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
    while (Clock::now() < deadline) {
      if (!temporaries().empty()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }
};

// --- 1. Inputs: the scene, its meshes, their .mtl and textures. --------------------------------

TEST_F(OwnedOutputs, ExportsBesideTheScenesMeshLeaveEveryInputAndAPointCacheFailsNamingIt) {
  // teapot.pc2's rest mesh would go to teapot.obj and teapot.mtl: the scene's own mesh and material.
  const fs::path scene = meshScene("teapot", "teapot.obj");
  const auto before = snapshot();
  const Result r = run({"export", scene.string(), "-o", path("teapot.pc2")});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, path("teapot.obj") + ": is the input file")) << r.output;
  EXPECT_TRUE(contains(r.output, "-o " + path("teapot_motion.pc2"))) << r.output;  // what to do
  EXPECT_EQ(changesSince(before), "");
  // .glb and .pvd beside the mesh share its stem only: they are written, every input untouched.
  for (const std::string name : {"teapot.glb", "teapot.pvd"}) {
    const Result w = run({"export", scene.string(), "-o", path(name)});
    EXPECT_EQ(w.status, 0) << w.output;
    EXPECT_TRUE(fs::exists(dir_ / name));
  }
  for (const auto& [file, bytes] : before) EXPECT_EQ(readFile(dir_ / file), bytes) << file;
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(OwnedOutputs, PointCacheWhoseMaterialIsTheMeshsMaterialFailsNamingIt) {
  // The mesh is shape.obj, its material library run.mtl: -o run.pc2 would write run.mtl.
  const fs::path scene = meshScene("scene", "shape.obj", "run.mtl");
  const auto before = snapshot();
  const Result r = run({"export", scene.string(), "-o", path("run.pc2")});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, path("run.mtl") + ": is the input file")) << r.output;
  EXPECT_EQ(changesSince(before), "");
}

TEST_F(OwnedOutputs, EveryWriterRefusesAFileTheSceneReads) {
  // check's --json and --trace, and a .glb export, named like the mesh, its material or texture.
  const fs::path scene = meshScene("scene", "teapot.obj", "teapot.mtl", "skin.glb");
  const auto before = snapshot();
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"check", scene.string(), "--json", path("teapot.obj")},
        std::vector<std::string>{"check", scene.string(), "--trace", path("teapot.mtl")},
        std::vector<std::string>{"export", scene.string(), "-o", path("skin.glb")}}) {
    const Result r = run(args);
    EXPECT_NE(r.status, 0) << r.output;
    EXPECT_TRUE(contains(r.output, ": is the input file")) << r.output;
    EXPECT_EQ(changesSince(before), "") << args[2] << " " << args[3];
  }
}

// --- 2. Companions and names springy chose replace only springy's own files. ------------------

TEST_F(OwnedOutputs, APointCachesCompanionReplacesOnlyWhatSpringyWrote) {
  const fs::path scene = meshScene("scene", "shape.obj");
  writeFile(dir_ / "run.obj", "# the user's own model, not an input of the scene\nv 0 0 0\n");
  const auto before = snapshot();
  Result r = run({"export", scene.string(), "-o", path("run.pc2")});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, path("run.obj") + ": exists and was not written by springy")) << r.output;
  EXPECT_EQ(changesSince(before), "");
  // Once it is gone, springy writes its own, and replaces them on the next export.
  fs::remove(dir_ / "run.obj");
  r = run({"export", scene.string(), "-o", path("run.pc2")});
  ASSERT_EQ(r.status, 0) << r.output;
  r = run({"export", scene.string(), "-o", path("run.pc2")});
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(OwnedOutputs, AnExportToAFolderReplacesOnlySpringysOwnFile) {
  // -o DIR names the export DIR/SCENE.glb itself: the user's model of that name stays.
  const fs::path scene = meshScene("scene", "shape.obj");
  fs::create_directories(dir_ / "out");
  writeFile(dir_ / "out" / "scene.glb", "the user's own model");
  const auto before = snapshot();
  const Result r = run({"export", scene.string(), "-o", path("out") + "/"});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, path("out/scene.glb") + ": exists and was not written by springy")) << r.output;
  EXPECT_EQ(changesSince(before), "");
}

// --- 3. Folders springy replaces keep what the user added. ------------------------------------

TEST_F(OwnedOutputs, AReportIntoItsOwnFolderKeepsTheUsersFile) {
  const fs::path scene = meshScene("scene", "shape.obj");
  const std::string report = path("report");
  Result r = run({"report", scene.string(), "-o", report, "--width", "64", "--height", "48"});
  ASSERT_EQ(r.status, 0) << r.output;
  writeFile(dir_ / "report" / "notes.txt", "the user's notes");
  const auto before = snapshot();
  r = run({"report", scene.string(), "-o", report, "--width", "64", "--height", "48"});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, report + "/notes.txt")) << r.output;
  EXPECT_EQ(changesSince(before), "");  // the notes and the earlier report, byte for byte
  EXPECT_TRUE(temporaries().empty());
  // A page the user edited is theirs too.
  fs::remove(dir_ / "report" / "notes.txt");
  writeFile(dir_ / "report" / "index.html", readFile(dir_ / "report" / "index.html") + "<!-- mine -->");
  r = run({"report", scene.string(), "-o", report, "--width", "64", "--height", "48"});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, report + "/index.html (changed since springy wrote it)")) << r.output;
  EXPECT_TRUE(contains(readFile(dir_ / "report" / "index.html"), "<!-- mine -->"));
}

TEST_F(OwnedOutputs, ASeriesFolderKeepsTheUsersFile) {
  const fs::path scene = meshScene("scene", "shape.obj");
  Result r = run({"export", scene.string(), "-o", path("run.pvd")});
  ASSERT_EQ(r.status, 0) << r.output;
  writeFile(dir_ / "run" / "analysis.py", "# the user's script");
  const auto before = snapshot();
  r = run({"export", scene.string(), "-o", path("run.pvd")});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, path("run/analysis.py"))) << r.output;
  EXPECT_EQ(changesSince(before), "");
}

// --- 4. Failed and interrupted runs leave no temporary file and the old outputs. -------------

TEST_F(OwnedOutputs, AFailedOrInterruptedExportLeavesNoTemporaryFileAndTheOldOutputs) {
  const std::string scene = tiny("scene.toml");
  for (const std::string name : {"run.glb", "run.pc2", "run.pvd"}) {
    ASSERT_EQ(run({"export", scene, "-o", path(name)}).status, 0);
  }
  const auto before = snapshot();
  // The scene made to blow up (explicit Euler, a long step, stiff struts).
  for (const std::string name : {"run.glb", "run.pc2", "run.pvd"}) {
    const Result r = run({"export", scene, "-o", path(name), "--integrator", "explicit_euler", "--dt", "0.01", "--set",
                          "body.strut_period=0.001", "--set", "body.strut_decay=1"});
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_TRUE(contains(r.output, "not exported: the run failed")) << r.output;
  }
  EXPECT_EQ(changesSince(before), "");
  EXPECT_TRUE(temporaries().empty());
  // A folder that does not exist: an error naming the file, nothing made.
  const Result r = run({"export", scene, "-o", path("missing/run.glb")});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, path("missing/run.glb"))) << r.output;
  EXPECT_EQ(changesSince(before), "");
  // SIGINT and SIGTERM stop the run; SIGQUIT (Ctrl-\) and SIGABRT end the process at once: its
  // handler removes the temporaries first (before, SIGQUIT left .run.tmp-XXXXXX.glb behind).
  for (const int signal : {SIGINT, SIGTERM, SIGQUIT, SIGABRT}) {
    for (const std::string name : {"run.glb", "run.pc2", "run.pvd"}) {
      Springy p({"export", scene, "-o", path(name), "--duration", "1000"}, {});
      ASSERT_TRUE(waitForTemporary()) << name;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));  // frames are being written
      p.signal(signal);
      const Result k = p.wait(30.0);
      EXPECT_TRUE(k.status == 128 + signal || k.killedBy == signal) << k.output;
      EXPECT_TRUE(temporaries().empty()) << name << " after signal " << signal;
      EXPECT_EQ(changesSince(before), "") << name << " after signal " << signal;
    }
  }
}

TEST_F(OwnedOutputs, AnInterruptedReportLeavesNoTemporaryFolderAndTheUsersFiles) {
  const std::string scene = tiny("scene.toml");
  const std::string report = path("report");
  ASSERT_EQ(run({"report", scene, "-o", report, "--width", "64", "--height", "48"}).status, 0);
  // With the user's file in it, the report refuses before it runs.
  writeFile(dir_ / "report" / "notes.txt", "the user's notes");
  const auto before = snapshot();
  Result r = run({"report", scene, "-o", report, "--width", "64", "--height", "48", "--duration", "1000"});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, report + "/notes.txt")) << r.output;
  EXPECT_TRUE(temporaries().empty());
  EXPECT_EQ(changesSince(before), "");
  // Without it, the report runs and a signal stops it: the earlier report stays as it was.
  fs::remove(dir_ / "report" / "notes.txt");
  const auto earlier = snapshot();
  for (const int signal : {SIGINT, SIGTERM}) {
    Springy p({"report", scene, "-o", report, "--width", "64", "--height", "48", "--duration", "1000"}, {});
    ASSERT_TRUE(waitForTemporary());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    p.signal(signal);
    r = p.wait(30.0);
    EXPECT_EQ(r.status, 128 + signal) << r.output;
    EXPECT_TRUE(temporaries().empty());
    EXPECT_EQ(changesSince(earlier), "");
  }
}

// --- 5. Output names. ---------------------------------------------------------------------------

TEST_F(OwnedOutputs, AnEmptyOutputNameIsAnError) {
  const fs::path scene = meshScene("scene", "shape.obj");
  const auto before = snapshot();
  for (const std::vector<std::string>& args : {
           std::vector<std::string>{"export", scene.string(), "-o", ""},
           std::vector<std::string>{"check", scene.string(), "--export", ""},
           std::vector<std::string>{"check", scene.string(), "--json", ""},
           std::vector<std::string>{"check", scene.string(), "--trace", ""},
           std::vector<std::string>{"render", scene.string(), "-o", ""},
           std::vector<std::string>{"frames", scene.string(), "-o", ""},
           std::vector<std::string>{"report", scene.string(), "-o", ""},
       }) {
    const Result r = run(args);
    EXPECT_NE(r.status, 0) << args[0] << " " << args[2] << ": " << r.output;
    EXPECT_TRUE(contains(r.output, args[2] == "-o" ? "--output" : args[2])) << r.output;
    EXPECT_TRUE(contains(r.output, "the output's name is empty")) << r.output;
  }
  EXPECT_EQ(changesSince(before), "");
}

TEST_F(OwnedOutputs, SeveralScenesToAFileNameAreAnError) {
  const fs::path a = meshScene("a", "shape.obj");
  const fs::path b = dir_ / "b.toml";
  fs::copy_file(a, b);
  const Result r = run({"export", a.string(), b.string(), "-o", path("one.glb")});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "-o " + path("one.glb") + ": 2 scenes make one export each")) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "one.glb"));
}

}  // namespace

// --- 5. Videos and stills springy names itself replace only springy's. --------------------------

namespace {

// The render's and the still's files carry springy's mark (render/image.h): a PNG's tEXt chunk
// "Software" and an MP4's comment, within their first bytes.
bool carriesTheMark(const fs::path& file) { return contains(readFile(file), "made with springy"); }

}  // namespace

TEST_F(OwnedOutputs, ARenderIntoAFolderReplacesOnlySpringysVideo) {
  const std::string scene = tiny("tiny.toml");
  fs::create_directories(dir_ / "out");
  writeFile(dir_ / "out" / "tiny.mp4", "the user's own video");
  const auto before = snapshot();
  const Result refused = run({"render", scene, "-o", path("out") + "/", "--duration", "0.2"});
  EXPECT_NE(refused.status, 0) << refused.output;
  EXPECT_TRUE(contains(refused.output, path("out/tiny.mp4") + ": exists and was not written by springy"))
      << refused.output;
  EXPECT_EQ(changesSince(before), "");
  fs::remove(dir_ / "out" / "tiny.mp4");
  ASSERT_EQ(run({"render", scene, "-o", path("out") + "/", "--duration", "0.2"}).status, 0);
  EXPECT_TRUE(carriesTheMark(dir_ / "out" / "tiny.mp4"));
  const Result again = run({"render", scene, "-o", path("out") + "/", "--duration", "0.3"});  // its own: replaced
  EXPECT_EQ(again.status, 0) << again.output;
  // A name the user gives is theirs to replace.
  writeFile(dir_ / "mine.mp4", "the user's own video");
  EXPECT_EQ(run({"render", scene, "-o", path("mine.mp4"), "--duration", "0.2"}).status, 0);
  EXPECT_TRUE(carriesTheMark(dir_ / "mine.mp4"));
}

TEST_F(OwnedOutputs, FramesReplaceOnlySpringysStillsAndSheet) {
  const std::string scene = tiny("tiny.toml");
  ASSERT_EQ(run({"frames", scene, "-o", path("out"), "--times", "0.1", "--sheet"}).status, 0);
  std::vector<fs::path> written;
  for (const auto& e : fs::directory_iterator(dir_ / "out")) written.push_back(e.path());
  ASSERT_EQ(written.size(), 2u);  // the still and the sheet
  for (const fs::path& file : written) {
    EXPECT_TRUE(carriesTheMark(file)) << file;
    // Still a PNG that reads back, the chunk's CRC right: stb refuses a bad CRC of a known chunk,
    // and a viewer would flag it; the test reads the chunk's bytes in place.
    const std::string bytes = readFile(file);
    EXPECT_EQ(bytes.substr(37, 4), "tEXt") << file;
  }
  EXPECT_EQ(run({"frames", scene, "-o", path("out"), "--times", "0.1", "--sheet"}).status, 0);  // its own
  for (const fs::path& file : written) {
    const auto keep = readFile(file);
    writeFile(file, "the user's own picture");
    const auto before = snapshot();
    const Result r = run({"frames", scene, "-o", path("out"), "--times", "0.1", "--sheet"});
    EXPECT_NE(r.status, 0) << r.output;
    EXPECT_TRUE(contains(r.output, file.string() + ": exists and was not written by springy")) << r.output;
    EXPECT_EQ(changesSince(before), "");  // refused before the run: the other file is not rewritten either
    writeFile(file, keep);
  }
}

// A report's subfolder is named after its scene, whatever the name holds: the folder's list reads
// such names back (a line break in the name split the list's line, so the next report refused
// its own folder as a user's).
TEST_F(OwnedOutputs, AReportOfAnOddlyNamedSceneReplacesItsOwnFolder) {
  const std::string scene = tiny(" odd\nname %41.toml");
  const Result first = run({"report", scene, "-o", path("r"), "--duration", "0.3"});
  ASSERT_EQ(first.status, 0) << first.output;
  EXPECT_TRUE(fs::is_directory(dir_ / "r" / " odd\nname %41")) << first.output;
  const Result second = run({"report", scene, "-o", path("r"), "--duration", "0.3"});
  EXPECT_EQ(second.status, 0) << second.output;
}
