// Golden state hashes: every scene in scenes/, stepped a few times with each integrator on one
// and on two threads, and tests/data/all_stages.toml and contact.toml through their first
// contacts, must reach exactly the state bits recorded in tests/data/golden.txt. Each run takes
// the step the command line would take (loadSceneWith, as `springy check --integrator NAME`):
// the scene's own, or for a scene that gives none the advisor's default (the count it tries
// first). A combination the command line refuses (vbd or backward Euler with moving colliders or
// soft attachments) is refused here too and has no hash. A
// change that alters results (a refactor must not) fails here; when the change is meant, run
//   SPRINGY_GOLDEN_UPDATE=1 build/tests/test_golden
// and say in the commit why the results moved.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "run/load.h"
#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/world.h"

namespace springy {
namespace {

namespace fs = std::filesystem;

const fs::path kGolden = fs::path(SPRINGY_SOURCE_DIR) / "tests" / "data" / "golden.txt";

std::map<std::string, std::string> readGolden() {
  std::map<std::string, std::string> table;
  std::ifstream in(kGolden);
  std::string key, hash;
  while (in >> key >> hash) table[key] = hash;
  return table;
}

std::string hex(uint64_t h) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

TEST(Golden, ShowcaseScenesReachTheRecordedStateOnOneAndTwoThreads) {
  const bool update = std::getenv("SPRINGY_GOLDEN_UPDATE") != nullptr;
  const std::map<std::string, std::string> golden = readGolden();
  std::map<std::string, std::string> now;
  std::vector<fs::path> scenes;
  for (const auto& entry : fs::directory_iterator(fs::path(SPRINGY_SOURCE_DIR) / "scenes")) {
    if (entry.path().extension() == ".toml") scenes.push_back(entry.path());
  }
  std::sort(scenes.begin(), scenes.end());
  ASSERT_GE(scenes.size(), 9u);
  // And a scene with every stage that reaches its contacts within the steps taken, and one whose
  // bodies meet (contact between bodies and self contact).
  scenes.push_back(fs::path(SPRINGY_SOURCE_DIR) / "tests" / "data" / "all_stages.toml");
  scenes.push_back(fs::path(SPRINGY_SOURCE_DIR) / "tests" / "data" / "contact.toml");
  for (const fs::path& path : scenes) {
    const bool throughContact = path.stem() == "all_stages" || path.stem() == "contact";
    for (Integrator integrator : {Integrator::ExplicitEuler, Integrator::SymplecticEuler, Integrator::VelocityVerlet,
                                  Integrator::Leapfrog, Integrator::RK4, Integrator::BackwardEuler,
                                  Integrator::BogackiShampine, Integrator::AdaptiveVerlet, Integrator::Vbd}) {
      const std::string key = path.stem().string() + "/" + std::string(integratorName(integrator));
      RunOptions overrides;
      overrides.integrator = std::string(integratorName(integrator));
      // Enough steps for every stage to act (the legacy cube's first step already has all its
      // struts); the implicit steps are costly on the bunnies, so fewer.
      const int steps = isImplicit(integrator) ? (throughContact ? 150 : 4) : (throughContact ? 400 : 40);
      std::string first;
      try {
        bool untried = false;
        const SceneDesc scene = loadSceneWith(path.string(), overrides, true, &untried);
        const Model model = buildModel(scene);
        for (unsigned threads : {1u, 2u}) {
          World world(model, scene.integrator, stepSize(scene));
          if (world.adaptive()) world.setTolerance(scene.tolerance);
          world.setIterations(scene.iterations);
          world.setThreads(threads, 0);
          for (int s = 0; s < steps; ++s) world.step();
          const std::string h = hex(stateHash(world));
          if (threads == 1) first = h;
          else EXPECT_EQ(h, first) << key << ": two threads differ from one";
        }
      } catch (const Error& e) {
        // Refused by the command line too (only the implicit integrators refuse scenes: moving
        // colliders, soft attachments); such a key must not have a hash.
        EXPECT_TRUE(isImplicit(integrator)) << key << ": refused: " << e.what();
        EXPECT_EQ(golden.count(key), 0u) << key << " has a hash but the command line refuses it: " << e.what();
        continue;
      }
      now[key] = first;
      if (update) continue;
      const auto it = golden.find(key);
      if (it == golden.end()) {
        ADD_FAILURE() << key << ": no recorded hash in " << kGolden << " (SPRINGY_GOLDEN_UPDATE=1 records it)";
        continue;
      }
      EXPECT_EQ(first, it->second) << key << ": the results changed. If that is meant, record the new hashes with "
                                   << "SPRINGY_GOLDEN_UPDATE=1 and say why in the commit";
    }
  }
  if (update) {
    std::ofstream out(kGolden);
    for (const auto& [key, hash] : now) out << key << ' ' << hash << '\n';
    std::printf("recorded %zu hashes in %s\n", now.size(), kGolden.c_str());
  }
}

}  // namespace
}  // namespace springy
