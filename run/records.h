// springy run: the results of a run as data. One SceneRecord per scene run, one BodyResult per
// body. `check --json` writes them, `check --junit` writes them as JUnit XML (a CI shows each
// scene's body as a test case), and `sweep` keeps them in each task's result and gathers its
// table from them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace springy {

using Json = nlohmann::ordered_json;  // keys in the order written: the same records, the same bytes

struct BodyResult {
  std::string name;
  std::uint64_t steps = 0;
  double time = 0.0;  // simulated [s]
  double maxStrain = 0.0, maxPenetration = 0.0;
  std::optional<double> volumeMin, volumeEnd;                // of rest; none for an open surface (a cloth)
  double kinetic = 0.0, gravitational = 0.0, elastic = 0.0;  // [J] at the end
  bool atRest = false;
};

struct SceneRecord {
  enum class Status { Ok, Failed, Error };  // ran and passed; ran and failed a check; could not run
  std::string path;                         // the scene file as given
  std::string scene;                        // its name
  Status status = Status::Ok;
  std::optional<std::uint32_t> failedBody;  // the body the failure names (Failed)
  std::string message;                      // the monitor's or the check's failure, or the error
  std::string integrator;
  double dt = 0.0, duration = 0.0;
  int substeps = 1;
  double wall = 0.0;  // [s] not part of the results proper: it differs between runs
  std::vector<BodyResult> bodies;
};

const char* statusName(SceneRecord::Status status);

// As JSON (`wall`: include the wall time). fromJson reads what toJson wrote; throws
// springy::Error naming `where` when a field is missing or of the wrong type.
Json toJson(const SceneRecord& record, bool wall = true);
SceneRecord recordFromJson(const Json& json, const std::string& where);

// `check --json FILE`: {"scenes": [records]}.
std::string recordsJson(const std::vector<SceneRecord>& records);
// `check --junit FILE`: a <testsuite> per scene, a <testcase> per body (classname: the scene's
// file), a <failure> with the message on the body that failed, an <error> test case for a scene
// that could not run. The attributes the JUnit schema (Ant's JUnit.xsd) requires are all there;
// the timestamp is now, local time, and the host this one.
std::string junitXml(const std::vector<SceneRecord>& records);

// Text for XML or HTML (an attribute's value or an element's text): & < > " ' as entities, control
// characters (not allowed in XML 1.0) but tab and line breaks as spaces.
std::string xmlEscaped(const std::string& text);

// A number in its shortest text that reads back to the same double ("0.1", "1e-05", "nan").
std::string exactNumber(double value);

}  // namespace springy
