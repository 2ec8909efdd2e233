// `springy study`, `springy suggest` and the time-step advice, run as a user runs them: the
// measured convergence orders match theory, the outputs exist, the advisor warns and picks
// substeps that make an unstable scene run.
#include <gtest/gtest.h>

#include "run_springy.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

using Result = springy::test::CommandResult;
Result run(const std::string& args) { return springy::test::runSpringy(args); }

const std::string kUnstable = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/app/unstable.toml";

fs::path tempDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("springy_study_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(StudyAccuracy, MeasuredOrdersMatchTheoryWithinTwoTenths) {
  const fs::path dir = tempDir("accuracy");
  const Result r = run("study accuracy --quick -o " + dir.string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(dir / "accuracy-orders.csv");
  ASSERT_TRUE(in) << "no accuracy-orders.csv";
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "case,integrator,order,theory,points");
  int checked = 0;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string name, integrator, order, theory, points;
    std::getline(s, name, ',');
    std::getline(s, integrator, ',');
    std::getline(s, order, ',');
    std::getline(s, theory, ',');
    std::getline(s, points, ',');
    EXPECT_GE(std::stoi(points), 2) << line;
    EXPECT_NEAR(std::stod(order), std::stod(theory), 0.2) << line;
    ++checked;
  }
  EXPECT_EQ(checked, 18);  // strut, hinge and gas x six integrators
  // The report: every point, a Markdown table with the machine, and the plots it references.
  EXPECT_TRUE(fs::exists(dir / "accuracy.csv"));
  std::ifstream md(dir / "accuracy.md");
  const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("Machine:"), std::string::npos);
  EXPECT_NE(text.find("| backward_euler |"), std::string::npos);
  EXPECT_NE(text.find("Artificial damping"), std::string::npos);
  if (std::system("command -v gnuplot > /dev/null 2>&1") == 0) {
    EXPECT_GT(fs::file_size(dir / "accuracy-strut.png"), 1000u);
    EXPECT_NE(text.find("](accuracy-strut.png)"), std::string::npos);
  }
  fs::remove_all(dir);
}

TEST(Advice, CheckWarnsWhenTheStepExceedsTheEstimatedLimit) {
  const Result r = run("check " + kUnstable + " --duration 0.2");
  EXPECT_EQ(r.status, 1) << r.output;  // and it does blow up
  EXPECT_NE(r.output.find("exceeds the estimated stable limit"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--substeps auto"), std::string::npos) << r.output;
}

TEST(Advice, SubstepsAutoMakesTheUnstableSceneRun) {
  const Result r = run("check " + kUnstable + " --duration 0.2 --substeps auto");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("--substeps auto: "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("exceeds the estimated"), std::string::npos) << r.output;
}

TEST(Advice, SubstepsRejectsWhatIsNeitherANumberNorAuto) {
  const Result r = run("check " + kUnstable + " --substeps lots");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("'auto'"), std::string::npos) << r.output;
}

TEST(Suggest, FlagsTheUnstableStepAndProposesParameters) {
  const Result r = run("suggest " + kUnstable);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("UNSTABLE"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("all time constants x"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("strut_period >="), std::string::npos) << r.output;
}

TEST(Suggest, NamesTheGasAndProposesALongerVolumePeriod) {
  const std::string scene = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/app/gas.toml";
  const Result r = run("suggest " + scene);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("0 hinges, gas)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("UNSTABLE"), std::string::npos) << r.output;
  // The gas alone limits the step: omega = 2 pi / 2 ms, so symplectic Euler needs
  // volume_period >= 2 pi dt / 2 / 0.9 (the advisor's safety factor) = 6.98 ms.
  const std::size_t at = r.output.find("volume_period >= ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const double proposed = std::stod(r.output.substr(at + 17));
  EXPECT_NEAR(proposed, 2 * 3.141592653589793 * 0.002 / 2 / 0.9, 0.05 * proposed) << r.output;
  // And the run at the scene's values is stopped, naming the body.
  const Result c = run("check " + scene);
  EXPECT_NE(c.status, 0);
  EXPECT_NE(c.output.find("body 'balloon'"), std::string::npos) << c.output;
  EXPECT_NE(c.output.find("/ volume_period)"), std::string::npos) << c.output;
}

}  // namespace
