// `springy gather MANIFEST` (and the end of a local sweep): the tasks' results as one table,
// table.csv and table.json, in task order, and for a check sweep whose scene varies two keys, a
// map of the grid, map-SCENE.png: stable or not, and the lowest volume, per point. Only results,
// never wall times, go into them: the same sweep gives the same bytes, wherever its tasks ran.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>

#include "app/atomic_file.h"
#include "app/csv.h"
#include "app/sweep.h"
#include "sim/error.h"

#ifdef SPRINGY_HAVE_IMAGES
#include "render/image.h"
#include "render/text.h"
#endif

namespace springy {
namespace {

namespace fs = std::filesystem;

// A point's value as a table cell: a string as it is, numbers and arrays as JSON.
std::string cell(const Json& value) { return value.is_string() ? value.get<std::string>() : value.dump(); }

std::string numberCell(const Json& value) {
  if (value.is_null()) return "";
  return value.is_string() ? value.get<std::string>() : value.dump();
}

// The keys of all points, in the order they first appear.
std::vector<std::string> pointKeys(const std::vector<SweepTask>& tasks) {
  std::vector<std::string> keys;
  for (const SweepTask& t : tasks) {
    for (const auto& [key, value] : t.point.items()) {
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
    }
  }
  return keys;
}

struct Row {
  const SweepTask* task;
  Json result;  // null when missing
};

std::string csvTable(const std::vector<Row>& rows, const std::vector<std::string>& keys) {
  static const char* kNumbers[] = {"steps",      "time",    "max_strain",    "max_penetration", "volume_min",
                                   "volume_end", "kinetic", "gravitational", "elastic"};
  std::string csv = "task,scene";
  for (const std::string& k : keys) csv += "," + csvField(k);
  csv += ",status,body";
  for (const char* n : kNumbers) csv += std::string(",") + n;
  csv += ",at_rest,outputs,message\n";
  for (const Row& row : rows) {
    std::string head = std::to_string(row.task->index) + "," + csvField(row.task->scene);
    for (const std::string& k : keys)
      head += "," + (row.task->point.contains(k) ? csvField(cell(row.task->point[k])) : "");
    const std::string status = row.result.is_null() ? "missing" : row.result["status"].get<std::string>();
    const std::string message = row.result.is_null() ? "" : row.result["message"].get<std::string>();
    std::string outputs;
    if (!row.result.is_null()) {
      for (const Json& f : row.result["outputs"]) outputs += (outputs.empty() ? "" : " ") + f.get<std::string>();
    }
    bool any = false;
    if (!row.result.is_null()) {
      for (const Json& record : row.result["records"]) {
        const std::string sceneStatus = record["status"].get<std::string>();
        const std::string failed = record["failed_body"].is_string() ? record["failed_body"].get<std::string>() : "";
        for (const Json& body : record["bodies"]) {
          any = true;
          const std::string name = body["body"].get<std::string>();
          // Each body's own verdict: the failure belongs to the body it names.
          const std::string bodyStatus = sceneStatus == "ok" ? "ok" : name == failed ? sceneStatus : "ok";
          csv += head + "," + bodyStatus + "," + csvField(name);
          for (const char* n : kNumbers) csv += "," + numberCell(body[n]);
          csv += std::string(",") + (body["at_rest"].get<bool>() ? "yes" : "no") + "," + csvField(outputs) + "," +
                 csvField(name == failed ? record["message"].get<std::string>() : "") + "\n";
        }
      }
    }
    if (!any) {
      csv += head + "," + status + ",";
      for (std::size_t i = 0; i < std::size(kNumbers); ++i) csv += ",";
      csv += ",," + csvField(outputs) + "," + csvField(message) + "\n";
      continue;
    }
  }
  return csv;
}

std::string jsonTable(const std::vector<Row>& rows) {
  Json table;
  table["tasks"] = Json::array();
  for (const Row& row : rows) {
    Json t;
    t["task"] = row.task->index;
    t["scene"] = row.task->scene;
    t["point"] = row.task->point;
    t["command"] = row.task->command;
    if (row.result.is_null()) {
      t["status"] = "missing";
      t["message"] = "";
      t["records"] = Json::array();
      t["outputs"] = Json::array();
    } else {
      t["status"] = row.result["status"];
      t["message"] = row.result["message"];
      t["records"] = Json::array();
      for (Json record : row.result["records"]) {
        record.erase("wall_s");  // differs between runs
        t["records"].push_back(std::move(record));
      }
      t["outputs"] = row.result["outputs"];
    }
    table["tasks"].push_back(std::move(t));
  }
  return table.dump(2) + "\n";
}

#ifdef SPRINGY_HAVE_IMAGES
// The lowest volume of any body of the task (of rest), or NaN (none: an open surface, no result).
double lowestVolume(const Json& result) {
  double lowest = std::numeric_limits<double>::quiet_NaN();
  if (result.is_null()) return lowest;
  for (const Json& record : result["records"]) {
    for (const Json& body : record["bodies"]) {
      if (body["volume_min"].is_number()) {
        const double v = body["volume_min"].get<double>();
        lowest = std::isnan(lowest) ? v : std::min(lowest, v);
      }
    }
  }
  return lowest;
}

// A grid's map: rows the first key's values, columns the second's; each cell green (stable) shaded
// by the lowest volume, red (failed: unstable or a check), grey (missing or an error).
render::Image drawMap(const std::string& title, const std::string& rowKey, const std::string& columnKey,
                      const std::vector<std::string>& rowValues, const std::vector<std::string>& columnValues,
                      const std::map<std::pair<std::size_t, std::size_t>, const Row*>& cells) {
  const render::Font font(render::kDefaultFontPath, 15.0f);
  const int pad = 10, line = font.lineHeight();
  int labelWidth = font.textWidth(rowKey);
  for (const std::string& v : rowValues) labelWidth = std::max(labelWidth, font.textWidth(v));
  int cellWidth = std::max(70, font.textWidth("unstable") + 12);
  for (const std::string& v : columnValues) cellWidth = std::max(cellWidth, font.textWidth(v) + 12);
  const int cellHeight = line + 12;
  const int left = pad + labelWidth + pad, top = pad + 2 * line + pad + line + 4;
  const std::string legend = "cells: the lowest volume of any body (of rest) where the run passed; red where it failed";
  render::Image image;
  image.width = std::max({left + cellWidth * static_cast<int>(columnValues.size()) + pad,
                          pad + font.textWidth(title) + pad, pad + font.textWidth(legend) + pad});
  image.width += image.width % 2;
  image.height = top + cellHeight * static_cast<int>(rowValues.size()) + pad + line + pad;
  image.height += image.height % 2;
  image.rgba.assign(static_cast<std::size_t>(image.width) * image.height * 4, 255);
  const glm::vec3 ink(0.1f, 0.1f, 0.12f);
  font.draw(image, pad, pad, title, ink);
  font.draw(image, pad, pad + line, "rows: " + rowKey + "; columns: " + columnKey, ink);
  for (std::size_t c = 0; c < columnValues.size(); ++c) {
    font.draw(image, left + static_cast<int>(c) * cellWidth + 6, top - line - 4, columnValues[c], ink);
  }
  for (std::size_t r = 0; r < rowValues.size(); ++r) {
    const int y = top + static_cast<int>(r) * cellHeight;
    font.draw(image, pad, y + 6, rowValues[r], ink);
    for (std::size_t c = 0; c < columnValues.size(); ++c) {
      const int x = left + static_cast<int>(c) * cellWidth;
      const auto it = cells.find({r, c});
      const Json* result = it == cells.end() ? nullptr : &it->second->result;
      const std::string status = !result || result->is_null() ? "missing" : (*result)["status"].get<std::string>();
      glm::vec3 colour(0.75f, 0.75f, 0.75f);
      std::string text = status;
      if (status == "failed") {
        colour = {0.86f, 0.33f, 0.3f};
        text = "unstable";
        if ((*result)["message"].get<std::string>().find("volume") != std::string::npos) text = "squashed";
      } else if (status == "ok") {
        const double v = lowestVolume(*result);
        // Yellow at half the rest volume or less, green at all of it.
        const float f = std::isnan(v) ? 1.0f : static_cast<float>(std::clamp((v - 0.5) / 0.5, 0.0, 1.0));
        colour = glm::vec3(0.95f, 0.85f, 0.35f) * (1.0f - f) + glm::vec3(0.45f, 0.8f, 0.45f) * f;
        char number[32];
        std::snprintf(number, sizeof number, "%.3f", v);
        text = std::isnan(v) ? "ok" : number;
      }
      render::fillRect(image, x + 1, y + 1, cellWidth - 2, cellHeight - 2, colour, 1.0f);
      font.draw(image, x + 6, y + 6, text, ink);
    }
  }
  font.draw(image, pad, image.height - pad - line, legend, ink);
  return image;
}

// Per scene of a check sweep whose points vary exactly two keys: map-SCENE.png.
void writeMaps(const std::vector<Row>& rows) {
  std::vector<std::string> scenes;
  for (const Row& row : rows) {
    if (std::find(scenes.begin(), scenes.end(), row.task->scene) == scenes.end()) scenes.push_back(row.task->scene);
  }
  for (const std::string& scene : scenes) {
    std::vector<const Row*> mine;
    for (const Row& row : rows) {
      if (row.task->scene == scene && row.task->command.front() == "check") mine.push_back(&row);
    }
    if (mine.empty()) continue;
    std::vector<std::string> varying;
    for (const auto& [key, value] : mine.front()->task->point.items()) {
      for (const Row* row : mine) {
        if (row->task->point.value(key, Json()) != value) {
          varying.push_back(key);
          break;
        }
      }
    }
    if (varying.size() != 2) continue;
    std::vector<std::string> values[2];
    std::map<std::pair<std::size_t, std::size_t>, const Row*> cells;
    for (const Row* row : mine) {
      std::size_t at[2];
      for (int k = 0; k < 2; ++k) {
        const std::string v = cell(row->task->point.value(varying[k], Json()));
        auto it = std::find(values[k].begin(), values[k].end(), v);
        at[k] = static_cast<std::size_t>(it - values[k].begin());
        if (it == values[k].end()) values[k].push_back(v);
      }
      cells[{at[0], at[1]}] = row;
    }
    const std::string stem = fs::path(scene).stem().string();
    const render::Image image =
        drawMap(stem + ": stable, and the lowest volume", varying[0], varying[1], values[0], values[1], cells);
    const std::string file = "map-" + stem + ".png";
    refuseUnlessOwned(file, "springy gather writes a map of that name");
    AtomicFile out(file);
    out.write(render::encodePng(image));
    out.commit();
    recordOwned(file);
    std::printf("gather: %s\n", file.c_str());
  }
}
#endif

}  // namespace

std::size_t gatherSweep(const std::vector<SweepTask>& tasks) {
  std::vector<Row> rows;
  std::size_t missing = 0, failed = 0, errors = 0;
  for (const SweepTask& t : tasks) {
    std::optional<Json> result = finishedResult(t);
    if (!result) {
      ++missing;
    } else if ((*result)["status"] == "failed") {
      ++failed;
    } else if ((*result)["status"] == "error") {
      ++errors;
    }
    rows.push_back({&t, result ? std::move(*result) : Json()});
  }
  writeOwnedFile("table.csv", csvTable(rows, pointKeys(tasks)), "springy gather writes a file of that name");
  writeOwnedFile("table.json", jsonTable(rows), "springy gather writes a file of that name");
#ifdef SPRINGY_HAVE_IMAGES
  writeMaps(rows);
#endif
  std::printf("gather: table.csv, table.json: %zu tasks, %zu ok, %zu failed, %zu errors, %zu missing\n", tasks.size(),
              tasks.size() - missing - failed - errors, failed, errors, missing);
  return missing;
}

}  // namespace springy
