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
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

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

TEST(StudyContact, ErrorsThroughContactFallWithTheStepAndTheTolerance) {
  // The cube's first 2 s (it lands at 1 s), every fixed-step integrator at 2, 1 and 0.5 ms,
  // both adaptive ones at 1e-3 and 1e-4 and vbd from a frame (1/30 s) down to 2 ms, against RK4
  // at 61 us.
  const fs::path dir = tempDir("contact");
  const Result r = run("study contact --quick --max-duration 2 --scenes " + std::string(SPRINGY_SOURCE_DIR) +
                       "/scenes/cube.toml -o " + dir.string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(dir / "accuracy-contact.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("scene,method,dt,tolerance,complete,centroid_rms,", 0), 0u) << line;
  std::map<std::string, std::vector<std::array<double, 3>>> rows;  // method -> (error, evaluations, energy lost)
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream s(line);
    for (std::string field; std::getline(s, field, ',');) f.push_back(field);
    ASSERT_EQ(f.size(), 13u) << line;
    EXPECT_EQ(f[4], "1") << "every run completes: " << line;
    rows[f[1]].push_back({std::stod(f[5]), std::stod(f[9]), std::stod(f[12])});
  }
  ASSERT_EQ(rows.size(), 7u);
  // vbd at 1/30, 1/60, ..., 1/480 s: first order through the landing too (its held vertices
  // bounce with the speed they arrived with); at a frame a step its numerical damping takes far
  // more of the cube's energy than symplectic Euler's at 2 ms (measured: 80 J against 4 J of the
  // reference's 1150 J of motion), and less at every smaller step.
  const auto& vbd = rows["vbd"];
  ASSERT_EQ(vbd.size(), 5u);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(vbd[k][0] / vbd[k + 1][0], 2.0, 0.5) << k;
  EXPECT_GT(vbd[0][2], 5.0 * rows["symplectic_euler"][0][2]);
  for (int k = 0; k < 4; ++k) EXPECT_LT(vbd[k + 1][2], vbd[k][2]) << k;
  // Symplectic Euler is first order through the landing: halving the step halves the error.
  const auto& euler = rows["symplectic_euler"];
  ASSERT_EQ(euler.size(), 3u);
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(euler[k][0] / euler[k + 1][0], 2.0, 0.5);
  // A tenfold tolerance buys a smaller error for more evaluations.
  for (const char* adaptive : {"bs32", "verlet_adaptive"}) {
    const auto& a = rows[adaptive];
    ASSERT_EQ(a.size(), 2u) << adaptive;
    EXPECT_LT(a[1][0], a[0][0] / 3) << adaptive;
    EXPECT_GT(a[1][1], a[0][1]) << adaptive;
  }
  std::ifstream md(dir / "accuracy-contact.md");
  const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("RK4 at twice that step differs from it by"), std::string::npos);
  EXPECT_NE(text.find("| verlet_adaptive | 1e-04 |"), std::string::npos);
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
  // Stiff springs, little damping: the stiffness sets the step.
  EXPECT_NE(r.output.find("set by its stiffest mode (omega "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("exceeds the estimated"), std::string::npos) << r.output;
}

// Reproduction of issue 21: the estimate at rest gives bunny_light 1 substep, and its landing
// (about 1.7 s) then gains energy. `--substeps auto` surveys the whole run and tries its count:
// the survey's count passes, so it halves it until a run fails (14, 7 pass; 4 fails at 1.6 s).
// The count it gives passes, and half of it fails when run alone: within a factor 2 of the fewest.
TEST(Advice, SubstepsAutoHoldsThroughTheBunnysLanding) {
  const std::string scene = std::string(SPRINGY_SOURCE_DIR) + "/scenes/bunny_light.toml";
  const std::string common = "check " + scene + " --duration 2.5 --threads 1 --substeps ";
  const Result r = run(common + "auto");
  EXPECT_EQ(r.status, 0) << r.output;
  const std::size_t at = r.output.find("--substeps auto: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const int n = std::stoi(r.output.substr(at + 17));
  EXPECT_NE(r.output.find("over the whole run"), std::string::npos) << r.output;
  // What sets the survey's estimate, and where (docs/stability.md: a hinge whose triangles have
  // nearly collapsed).
  EXPECT_NE(r.output.find("set by its most damped mode (rate "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" around its vertex "), std::string::npos) << r.output;
  const std::size_t surveyed = r.output.find("substeps), at t = ");
  ASSERT_NE(surveyed, std::string::npos) << r.output;
  const int first = std::stoi(r.output.substr(r.output.rfind('(', surveyed) + 1));
  EXPECT_LT(n, first) << r.output;  // the survey's estimate is the safe side: fewer substeps pass
  const std::size_t failed = r.output.find(", and failed at ");
  ASSERT_NE(failed, std::string::npos) << r.output;
  const int half = std::stoi(r.output.substr(failed + 16));
  EXPECT_EQ(half, (n + 1) / 2) << r.output;
  for (const int fewer : {1, half}) {
    const Result f = run(common + std::to_string(fewer));
    EXPECT_EQ(f.status, 1) << fewer << " substeps: " << f.output;
    EXPECT_NE(f.output.find("total energy rose"), std::string::npos) << f.output;
    EXPECT_GT(n, fewer);
  }
}

// What a try reported as failing fails when run alone at that count.
void expectTheRunFails(const std::string& scene, int substeps) {
  const Result f = run("check " + scene + " --threads 1 --substeps " + std::to_string(substeps));
  EXPECT_EQ(f.status, 1) << f.output;
  EXPECT_NE(f.output.find("total energy rose"), std::string::npos) << f.output;
}

// A user's mesh given only a mass: the survey's run meets softer shapes at the landing than a run
// at its proposal does, and that run fails (tests/data/app/bunny_body.toml). `--substeps auto`
// tries its count and doubles it until the run passes; what it reports is true: the count it
// tried first fails, and the one it gives passes.
TEST(Advice, SubstepsAutoTriesItsCountOverTheWholeRun) {
  const std::string scene = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/app/bunny_body.toml";
  const std::string common = "check " + scene + " --threads 1 --substeps ";
  const Result r = run(common + "auto");
  EXPECT_EQ(r.status, 0) << r.output;
  const std::size_t tried = r.output.find(": trying ");
  ASSERT_NE(tried, std::string::npos) << r.output;
  const int first = std::stoi(r.output.substr(tried + 9));
  const std::size_t at = r.output.find("--substeps auto: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const int n = std::stoi(r.output.substr(at + 17));
  EXPECT_NE(r.output.find("the run failed at " + std::to_string(first) + " (after t = "), std::string::npos)
      << r.output;
  EXPECT_GE(n, 2 * first);
  expectTheRunFails(scene, first);
}

// The same bunny with no step given: the advisor's default step (half its estimate at rest) fails
// at the landing (check's own run is its try); twice the substeps and more are tried like
// --substeps auto's count, and the run at the count that passed passes.
TEST(Advice, TheDefaultStepIsTriedOverTheWholeRun) {
  const std::string scene = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/app/bunny_body.toml";
  const std::string trace = testing::TempDir() + "default_step_trace.csv";
  const Result r = run("check " + scene + " --threads 1 --trace " + trace);
  EXPECT_EQ(r.status, 0) << r.output;
  {  // the rows of the run that passed, none of the failed one's: 1.75 s at 30 frames/s
    std::ifstream in(trace);
    std::string line;
    int rows = -1;  // header
    while (std::getline(in, line)) ++rows;
    EXPECT_EQ(rows, 53) << r.output;
  }
  std::filesystem::remove(trace);
  const std::size_t failed = r.output.find("the run failed at ");
  ASSERT_NE(failed, std::string::npos) << r.output;
  const int first = std::stoi(r.output.substr(failed + 18));
  const std::size_t given = r.output.find(" s / ");
  ASSERT_NE(given, std::string::npos) << r.output;
  EXPECT_GE(std::stoi(r.output.substr(given + 5)), 2 * first) << r.output;
  expectTheRunFails(scene, first);
}

// A failure a smaller step does not move (a cube through a collider from the start) stops the
// tries after three at the same moment, and says so: the search does not run on to 32 times the
// substeps (it did: 16 minutes on a 3.5 s cloth scene whose cloth swung through a bar's rim).
TEST(Advice, AFailureThatDoesNotMoveWithTheStepEndsTheTries) {
  const std::string scene = testing::TempDir() + "through_blade.toml";
  std::ofstream(scene) << "[scene]\nduration = 0.5\n[environment]\ngravity = [0, 0, 0]\n"
                          "[[body]]\nname = \"cube\"\nshape = \"cube\"\nsize = 0.5\nposition = [0, 1, 0]\n"
                          "[[triangles]]\nname = \"blade\"\n"
                          "quads = [[[-1, 1.0, -1], [-1, 1.0, 1], [1, 1.0, 1], [1, 1.0, -1]]]\n";
  const Result r = run("check " + scene + " --threads 1");
  std::filesystem::remove(scene);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("so a smaller step does not fix it: body 'cube'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("passes through collider 'blade'"), std::string::npos) << r.output;
  int tries = 0;
  for (std::size_t at = r.output.find(": trying "); at != std::string::npos; at = r.output.find(": trying ", at + 1)) {
    ++tries;
  }
  // Check's own run (1 substep, failing), then 2, 4 and 8, failing at the same frame: stop.
  EXPECT_EQ(tries, 3) << r.output;
  EXPECT_NE(r.output.find("at 2, 4 and 8 substeps"), std::string::npos) << r.output;
}

// `check` runs a default step once: its own run, monitored as a try is, is the try (it ran the
// scene twice before: the advisor's try, then the check). The cloth scene gives no step.
TEST(Advice, CheckRunsADefaultStepThatPassesOnce) {
  const std::string scene = std::string(SPRINGY_SOURCE_DIR) + "/tests/data/app/cloth.toml";
  const Result r = run("check " + scene + " --threads 1");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("): the scene gives none, so the advisor's: at most "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("; this run is its try"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("over the whole run"), std::string::npos) << r.output;  // no separate try
  const std::size_t header = r.output.find(": Cloth, 2 bodies");
  ASSERT_NE(header, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(": Cloth, 2 bodies", header + 1), std::string::npos) << r.output;  // one run
}

// Backward Euler is stable at any step on its springs, but the contact between bodies acts after
// its solve, on single vertices (sim/stability.h): on the column the landing of the middle body
// on the bottom one gains energy at 1 substep (2 ms, t = 0.3 s) and at 2 (t = 0.47 s). Before,
// `--substeps auto` called backward Euler unconditionally stable and gave it 1. Now it takes
// symplectic Euler's limit and says why, and its count runs.
TEST(Advice, SubstepsAutoHoldsBackwardEulerWhereBodiesMeet) {
  const std::string scene = std::string(SPRINGY_SOURCE_DIR) + "/scenes/column.toml";
  const std::string common = "check " + scene + " --integrator backward_euler --duration 0.6 --threads 1 --substeps ";
  const Result r = run(common + "auto");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("contact between bodies acts after the implicit solve"), std::string::npos) << r.output;
  const std::size_t at = r.output.find("--substeps auto: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const int n = std::stoi(r.output.substr(at + 17));
  for (const int fewer : {1, 2}) {
    const Result f = run(common + std::to_string(fewer));
    EXPECT_EQ(f.status, 1) << fewer << " substeps: " << f.output;
    EXPECT_NE(f.output.find("total energy of the bodies in contact"), std::string::npos) << f.output;
    EXPECT_GT(n, fewer);
  }
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
  // The gas alone limits the step: omega = 2 pi / 2 ms, so symplectic Euler needs omega dt <= sqrt 2
  // (its energy swing from rest doubles there, sim/stability.cpp stableAt), volume_period >=
  // 2 pi dt / sqrt 2 / 0.9 (the advisor's safety factor) = 9.87 ms.
  const std::size_t at = r.output.find("volume_period >= ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const double proposed = std::stod(r.output.substr(at + 17));
  EXPECT_NEAR(proposed, 2 * 3.141592653589793 * 0.002 / std::sqrt(2.0) / 0.9, 0.05 * proposed) << r.output;
  // And the run at the scene's values is stopped, naming the body.
  const Result c = run("check " + scene);
  EXPECT_NE(c.status, 0);
  EXPECT_NE(c.output.find("body 'balloon'"), std::string::npos) << c.output;
  EXPECT_NE(c.output.find("/ volume_period)"), std::string::npos) << c.output;
}

TEST(Suggest, PredictsTheSquashAndPeriodsThatKeepTheVolume) {
  // A soft ball of the body material dropped 2 m: suggest predicts that it loses more than 15%
  // of its volume, and proposes stretch and bend periods; with them, check's 85% floor holds,
  // and without them it is broken.
  const fs::path dir = tempDir("squash");
  const std::string ball =
      "[scene]\nduration = 1.5\n[[body]]\nshape = \"icosphere\"\nsubdivisions = 2\nposition = [0.0, 3.0, 0.0]\n"
      "mass = 1.0\n";
  std::ofstream(dir / "soft.toml") << ball << "stretch_period = 0.4\nbend_period = 3.0\n[[plane]]\n";
  const Result r = run("suggest " + (dir / "soft.toml").string() + " --keep-volume 0.85");
  ASSERT_EQ(r.status, 0) << r.output;
  const std::size_t lowest = r.output.find("lowest volume ");
  ASSERT_NE(lowest, std::string::npos) << r.output;
  EXPECT_LT(std::stod(r.output.substr(lowest + 14)), 85.0) << r.output;
  const std::size_t at = r.output.find("to keep 85%: stretch_period = ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const double stretch = std::stod(r.output.substr(at + 30));
  const std::size_t bendAt = r.output.find("bend_period = ", at);
  ASSERT_NE(bendAt, std::string::npos) << r.output;
  const double bend = std::stod(r.output.substr(bendAt + 14));
  EXPECT_LT(stretch, 0.4);
  EXPECT_LT(bend, 3.0);
  std::ofstream(dir / "stiffer.toml") << ball << "stretch_period = " << stretch << "\nbend_period = " << bend
                                      << "\n[[plane]]\n";
  const Result soft = run("check " + (dir / "soft.toml").string() + " --min-volume 0.85");
  EXPECT_NE(soft.status, 0) << soft.output;
  EXPECT_NE(soft.output.find("shorter bend_period or stretch_period"), std::string::npos) << soft.output;
  const Result stiffer = run("check " + (dir / "stiffer.toml").string() + " --min-volume 0.85");
  EXPECT_EQ(stiffer.status, 0) << stiffer.output;
  // With no step in the scene, springy chooses one with a margin for impacts: 0.5 of the
  // estimate for the body material, 0.2 when a body has the element material.
  EXPECT_NE(soft.output.find("at most 0.5 of the estimated stable limit"), std::string::npos) << soft.output;
  std::ofstream(dir / "element.toml") << ball << "strut_period = 0.07\n[[plane]]\n";
  const Result element = run("check " + (dir / "element.toml").string() + " --duration 0.1");
  EXPECT_EQ(element.status, 0) << element.output;
  EXPECT_NE(element.output.find("at most 0.2 of the estimated stable limit"), std::string::npos) << element.output;
  // A body that holds its shape is said to.
  std::ofstream(dir / "default.toml") << ball << "[[plane]]\n";
  const Result plain = run("suggest " + (dir / "default.toml").string());
  EXPECT_NE(plain.output.find("holds its shape"), std::string::npos) << plain.output;
  fs::remove_all(dir);
}

}  // namespace

// A study's pages share their folder with other files (-o docs): a file of a name the study
// writes that springy did not write (the folder's record, .springy-files, does not list it as it
// is) stops the study before it runs, the file kept; the study's own files are replaced.
TEST(StudyOwnership, AUsersFileOfAStudysNameStopsItBeforeTheRunAndItsOwnAreReplaced) {
  const fs::path dir = tempDir("owned");
  const std::string study = "study contact --quick --max-duration 0.5 --scenes " + std::string(SPRINGY_SOURCE_DIR) +
                            "/scenes/cube.toml -o " + dir.string();
  std::ofstream(dir / "accuracy-contact.md") << "my notes";
  std::ofstream(dir / "notes.md") << "another file: not the study's name";
  const Result refused = run(study);
  EXPECT_EQ(refused.status, 1) << refused.output;
  EXPECT_NE(refused.output.find("that springy did not write"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find(": accuracy-contact.md;"), std::string::npos) << refused.output;
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}), 2);  // nothing written
  std::ifstream in(dir / "accuracy-contact.md");
  std::string kept;
  std::getline(in, kept);
  EXPECT_EQ(kept, "my notes");
  fs::remove(dir / "accuracy-contact.md");
  const Result first = run(study);
  ASSERT_EQ(first.status, 0) << first.output;
  const Result again = run(study);  // its own files, as it wrote them
  EXPECT_EQ(again.status, 0) << again.output;
  std::ifstream record(dir / ".springy-files");
  std::stringstream listed;
  listed << record.rdbuf();
  EXPECT_NE(listed.str().find(" accuracy-contact.csv\n"), std::string::npos) << listed.str();
  EXPECT_EQ(listed.str().find("notes.md"), std::string::npos) << listed.str();
  fs::remove_all(dir);
}
