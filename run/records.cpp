#include "run/records.h"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "sim/error.h"

namespace springy {

std::string xmlEscaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        // XML 1.0 allows no control characters but tab, newline and carriage return.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') {
          out += ' ';
        } else {
          out += c;
        }
    }
  }
  return out;
}

namespace {

// JSON has no NaN or infinity: those (a blown-up run's energies) are written as strings.
Json number(double value) { return std::isfinite(value) ? Json(value) : Json(exactNumber(value)); }

double readNumber(const Json& json, const char* key, const std::string& where) {
  const auto it = json.find(key);
  if (it == json.end()) throw Error(where + ": no \"" + key + "\"");
  if (it->is_number()) return it->get<double>();
  if (it->is_string()) {
    const std::string text = it->get<std::string>();
    if (text == "nan") return std::nan("");
    if (text == "inf") return INFINITY;
    if (text == "-inf") return -INFINITY;
  }
  throw Error(where + ": \"" + key + "\" is not a number");
}

template <class T>
T read(const Json& json, const char* key, const std::string& where) {
  const auto it = json.find(key);
  if (it == json.end()) throw Error(where + ": no \"" + key + "\"");
  try {
    return it->get<T>();
  } catch (const Json::exception&) {
    throw Error(where + ": \"" + key + "\" has the wrong type");
  }
}

}  // namespace

std::string exactNumber(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char text[64];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

const char* statusName(SceneRecord::Status status) {
  switch (status) {
    case SceneRecord::Status::Ok: return "ok";
    case SceneRecord::Status::Failed: return "failed";
    case SceneRecord::Status::Error: return "error";
  }
  return "error";
}

Json toJson(const SceneRecord& r, bool wall) {
  Json j;
  j["path"] = r.path;
  j["scene"] = r.scene;
  j["status"] = statusName(r.status);
  j["failed_body"] = r.failedBody ? Json(r.bodies.at(*r.failedBody).name) : Json(nullptr);
  j["message"] = r.message;
  j["integrator"] = r.integrator;
  j["dt"] = number(r.dt);
  j["substeps"] = r.substeps;
  j["duration"] = number(r.duration);
  if (wall) j["wall_s"] = number(r.wall);
  Json bodies = Json::array();
  for (const BodyResult& b : r.bodies) {
    Json body;
    body["body"] = b.name;
    body["steps"] = b.steps;
    body["time"] = number(b.time);
    body["max_strain"] = number(b.maxStrain);
    body["max_penetration"] = number(b.maxPenetration);
    body["volume_min"] = b.volumeMin ? number(*b.volumeMin) : Json(nullptr);
    body["volume_end"] = b.volumeEnd ? number(*b.volumeEnd) : Json(nullptr);
    body["kinetic"] = number(b.kinetic);
    body["gravitational"] = number(b.gravitational);
    body["elastic"] = number(b.elastic);
    body["at_rest"] = b.atRest;
    bodies.push_back(std::move(body));
  }
  j["bodies"] = std::move(bodies);
  return j;
}

SceneRecord recordFromJson(const Json& j, const std::string& where) {
  if (!j.is_object()) throw Error(where + ": a scene record is not an object");
  SceneRecord r;
  r.path = read<std::string>(j, "path", where);
  r.scene = read<std::string>(j, "scene", where);
  const std::string status = read<std::string>(j, "status", where);
  if (status == "ok") {
    r.status = SceneRecord::Status::Ok;
  } else if (status == "failed") {
    r.status = SceneRecord::Status::Failed;
  } else if (status == "error") {
    r.status = SceneRecord::Status::Error;
  } else {
    throw Error(where + ": unknown status '" + status + "'");
  }
  r.message = read<std::string>(j, "message", where);
  r.integrator = read<std::string>(j, "integrator", where);
  r.dt = readNumber(j, "dt", where);
  r.substeps = read<int>(j, "substeps", where);
  r.duration = readNumber(j, "duration", where);
  if (j.contains("wall_s")) r.wall = readNumber(j, "wall_s", where);
  const std::string failed =
      j.contains("failed_body") && j["failed_body"].is_string() ? j["failed_body"].get<std::string>() : std::string();
  for (const Json& b : read<Json>(j, "bodies", where)) {
    BodyResult body;
    body.name = read<std::string>(b, "body", where);
    body.steps = read<std::uint64_t>(b, "steps", where);
    body.time = readNumber(b, "time", where);
    body.maxStrain = readNumber(b, "max_strain", where);
    body.maxPenetration = readNumber(b, "max_penetration", where);
    if (b.contains("volume_min") && !b["volume_min"].is_null()) body.volumeMin = readNumber(b, "volume_min", where);
    if (b.contains("volume_end") && !b["volume_end"].is_null()) body.volumeEnd = readNumber(b, "volume_end", where);
    body.kinetic = readNumber(b, "kinetic", where);
    body.gravitational = readNumber(b, "gravitational", where);
    body.elastic = readNumber(b, "elastic", where);
    body.atRest = read<bool>(b, "at_rest", where);
    if (!failed.empty() && body.name == failed && !r.failedBody) {
      r.failedBody = static_cast<std::uint32_t>(r.bodies.size());
    }
    r.bodies.push_back(std::move(body));
  }
  return r;
}

std::string recordsJson(const std::vector<SceneRecord>& records) {
  Json all;
  all["scenes"] = Json::array();
  for (const SceneRecord& r : records) all["scenes"].push_back(toJson(r));
  return all.dump(2) + "\n";
}

std::string junitXml(const std::vector<SceneRecord>& records) {
  // The schema's timestamp: local time, no zone (xs:dateTime as Ant writes it).
  char timestamp[32] = "1970-01-01T00:00:00";
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  if (localtime_r(&now, &local)) std::strftime(timestamp, sizeof timestamp, "%Y-%m-%dT%H:%M:%S", &local);
  char host[256] = "localhost";
  if (gethostname(host, sizeof host) != 0) std::snprintf(host, sizeof host, "localhost");
  host[sizeof host - 1] = '\0';
  const std::string hostname = host;
  std::size_t tests = 0, failures = 0, errors = 0;
  double wall = 0.0;
  std::string suites;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const SceneRecord& r = records[i];
    const bool error = r.status == SceneRecord::Status::Error;
    const std::size_t cases = error ? 1 : r.bodies.size();
    const std::size_t failed = r.status == SceneRecord::Status::Failed ? 1 : 0;
    tests += cases;
    failures += failed;
    errors += error ? 1 : 0;
    wall += r.wall;
    const std::string time = exactNumber(r.wall);
    const std::string classname = xmlEscaped(r.path);
    suites += "  <testsuite name=\"" + classname + "\" tests=\"" + std::to_string(cases) + "\" failures=\"" +
              std::to_string(failed) + "\" errors=\"" + (error ? "1" : "0") + "\" skipped=\"0\" time=\"" + time +
              "\" timestamp=\"" + std::string(timestamp) + "\" hostname=\"" + xmlEscaped(hostname) + "\" id=\"" +
              std::to_string(i) + "\" package=\"springy\">\n";
    if (error) {
      suites += "    <testcase name=\"(scene)\" classname=\"" + classname + "\" time=\"" + time + "\">\n" +
                "      <error message=\"" + xmlEscaped(r.message) + "\" type=\"error\">" + xmlEscaped(r.message) +
                "</error>\n    </testcase>\n";
    }
    for (std::size_t b = 0; b < r.bodies.size() && !error; ++b) {
      suites += "    <testcase name=\"" + xmlEscaped(r.bodies[b].name) + "\" classname=\"" + classname + "\" time=\"" +
                time + "\"";
      if (r.failedBody == b) {
        suites += ">\n      <failure message=\"" + xmlEscaped(r.message) + "\" type=\"failed\">" +
                  xmlEscaped(r.message) + "</failure>\n    </testcase>\n";
      } else {
        suites += "/>\n";
      }
    }
    suites += "    <system-out/>\n    <system-err/>\n  </testsuite>\n";
  }
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites name=\"springy check\" tests=\"" +
         std::to_string(tests) + "\" failures=\"" + std::to_string(failures) + "\" errors=\"" + std::to_string(errors) +
         "\" time=\"" + exactNumber(wall) + "\">\n" + suites + "</testsuites>\n";
}

}  // namespace springy
