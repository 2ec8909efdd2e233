// Inputs the fuzzers (fuzz/, scripts/fuzz.sh) once crashed on, kept as regressions: each scene in
// fuzz/regressions/scene/ goes through parseScene and buildModel, each mesh file in
// fuzz/regressions/mesh/ (its extension in its name) through readMeshFile, weldVertices,
// loadClosedMesh and simplifyMesh, each scene in fuzz/regressions/motion/ through a few steps,
// each input in fuzz/regressions/set/ as --set settings over a scene, exactly as in the fuzz
// targets (fuzz/fuzz_inputs.h). Each must
// load or be rejected with springy::Error; any other exception fails the test, and a crash or a
// sanitizer report (CI's ASan pass) fails the test binary. fuzz/README.md says how a crash
// becomes a file here.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz/fuzz_inputs.h"

namespace {

namespace fs = std::filesystem;

const fs::path kRegressions = fs::path(SPRINGY_SOURCE_DIR) / "fuzz" / "regressions";

// The regular files of a directory, sorted; dot files (.gitkeep) and README.md left out.
std::vector<fs::path> inputsIn(const fs::path& dir) {
  std::vector<fs::path> files;
  if (!fs::is_directory(dir)) return files;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (e.is_regular_file() && name[0] != '.' && name != "README.md") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A test name from a file name: letters and digits kept, everything else '_'.
std::string testName(const ::testing::TestParamInfo<fs::path>& info) {
  std::string name = info.param.filename().string();
  for (char& c : name) {
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'))) c = '_';
  }
  return name + "_" + std::to_string(info.index);
}

// As in the fuzz targets: a crash contained in readMeshFile's child process stays quiet.
const bool kQuietChildren = (springy::fuzz::defaultCrashSignalsInForkedChildren(), true);

TEST(FuzzRegressions, DirectoriesExist) {
  EXPECT_TRUE(kQuietChildren);
  EXPECT_TRUE(fs::is_directory(kRegressions / "scene"));
  EXPECT_TRUE(fs::is_directory(kRegressions / "mesh"));
  EXPECT_TRUE(fs::is_directory(kRegressions / "motion"));
  EXPECT_TRUE(fs::is_directory(kRegressions / "set"));
}

class SceneRegression : public ::testing::TestWithParam<fs::path> {};

TEST_P(SceneRegression, LoadsOrFailsWithError) {
  const std::string text = readAll(GetParam());
  EXPECT_NO_THROW(springy::fuzz::runScene(text, springy::fuzz::scenePath(SPRINGY_SOURCE_DIR))) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Fuzz, SceneRegression, ::testing::ValuesIn(inputsIn(kRegressions / "scene")), testName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(SceneRegression);

class MeshRegression : public ::testing::TestWithParam<fs::path> {};

TEST_P(MeshRegression, LoadsOrFailsWithError) {
  EXPECT_NO_THROW(springy::fuzz::runMeshFile(GetParam().string())) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Fuzz, MeshRegression, ::testing::ValuesIn(inputsIn(kRegressions / "mesh")), testName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(MeshRegression);

class MotionRegression : public ::testing::TestWithParam<fs::path> {};

TEST_P(MotionRegression, StepsOrFailsWithError) {
  const std::string text = readAll(GetParam());
  EXPECT_NO_THROW(springy::fuzz::runSceneSteps(text, springy::fuzz::scenePath(SPRINGY_SOURCE_DIR))) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Fuzz, MotionRegression, ::testing::ValuesIn(inputsIn(kRegressions / "motion")), testName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(MotionRegression);

class SetRegression : public ::testing::TestWithParam<fs::path> {};

TEST_P(SetRegression, LoadsOrFailsWithError) {
  const std::string bytes = readAll(GetParam());
  EXPECT_NO_THROW(springy::fuzz::runSettings(SPRINGY_SOURCE_DIR, reinterpret_cast<const uint8_t*>(bytes.data()),
                                             bytes.size()))
      << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Fuzz, SetRegression, ::testing::ValuesIn(inputsIn(kRegressions / "set")), testName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(SetRegression);

// The --set target splits its input as the command line would see one setting per --set.
TEST(FuzzInputs, SettingsAreTheLinesAfterTheSceneByte) {
  EXPECT_EQ(springy::fuzz::settingsOf("a=1\nbody.mass=2"), (std::vector<std::string>{"a=1", "body.mass=2"}));
  EXPECT_EQ(springy::fuzz::settingsOf(""), (std::vector<std::string>{""}));
  EXPECT_EQ(springy::fuzz::settingsOf("x=1\n"), (std::vector<std::string>{"x=1", ""}));
  EXPECT_EQ(springy::fuzz::setScenePath("S", 0), "S/scenes/single_sphere.toml");
  EXPECT_EQ(springy::fuzz::setScenePath("S", springy::fuzz::kSetSceneCount + 2), "S/scenes/press.toml");
}

// A scene that moves: the motion target steps it, and its error is the scene's.
TEST(FuzzInputs, TheMotionTargetStepsAMovingSceneAndRejectsABadOne) {
  const std::string path = springy::fuzz::scenePath(SPRINGY_SOURCE_DIR);
  EXPECT_TRUE(springy::fuzz::runSceneSteps(readAll(fs::path(SPRINGY_SOURCE_DIR) / "scenes" / "press.toml"), path));
  EXPECT_FALSE(springy::fuzz::runSceneSteps("[[plane]]\nmotion = { spin = 1e9 }\n", path));
}

}  // namespace
