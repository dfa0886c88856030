// Dataset manifest reader (format written by engine/sim/dataset.cpp).
#include "engine/rollout/dataset_split.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "engine/core/error.h"
#include "engine/io/temp_file.h"

namespace dynscope {

DatasetSplit read_dataset_split(const std::string& dir, const std::string& split) {
  if (split != "train" && split != "val" && split != "test" && split != "all") {
    throw ValueError("split", "unknown split '" + split + "' (train, val, test or all)");
  }
  namespace fs = std::filesystem;
  const std::string path = (fs::path(dir) / "manifest.json").string();
  if (!fs::is_directory(dir)) throw IoError(dir, "dataset directory does not exist");
  const std::string text = read_text_file(
      path, "cannot open dataset manifest (is this a `dynscope generate` output directory?)");
  nlohmann::json m;
  try {
    m = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(path, "manifest", std::string("malformed JSON: ") + e.what());
  }
  DatasetSplit out;
  out.dir = dir;
  out.split = split;
  try {
    out.scenario = m.at("scenario").get<std::string>();
    std::map<std::string, int> outcome;
    if (m.contains("files")) {
      for (const auto& f : m.at("files")) {
        outcome[f.at("file").get<std::string>()] = f.value("outcome", -1);
      }
    }
    std::vector<std::string> files;
    for (const char* name : {"train", "val", "test"}) {
      if (split != "all" && split != name) continue;
      for (const auto& f : m.at("split").at(name)) files.push_back(f.get<std::string>());
    }
    for (const std::string& f : files) {
      DatasetItem item;
      item.file = f;
      item.path = (fs::path(dir) / item.file).string();
      const auto it = outcome.find(item.file);
      item.outcome = it == outcome.end() ? -1 : it->second;
      if (!fs::exists(item.path)) {
        throw FormatError(path, "split/" + split, "lists " + item.file + ", which does not exist");
      }
      out.items.push_back(item);
    }
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(path, "manifest", std::string("missing or malformed field: ") + e.what());
  }
  return out;
}

DatasetSplit evenly_spaced_sample(const DatasetSplit& split, int max_scenes) {
  if (max_scenes < 1) {
    throw ValueError("max_scenes", "must be >= 1, got " + std::to_string(max_scenes));
  }
  const size_t m = split.items.size();
  const auto n = static_cast<size_t>(max_scenes);
  if (m <= n) return split;
  DatasetSplit out = split;
  out.items.clear();
  for (size_t i = 0; i < n; ++i) out.items.push_back(split.items[i * m / n]);
  out.split =
      split.split + ", " + std::to_string(n) + " of " + std::to_string(m) + " evenly spaced";
  return out;
}

DatasetSplit read_dataset_splits(const std::vector<std::string>& dirs, const std::string& split,
                                 int max_scenes) {
  if (max_scenes < 0) {
    throw ValueError("max_scenes",
                     "must be >= 0 (0: every scene), got " + std::to_string(max_scenes));
  }
  if (dirs.empty()) throw ValueError("data", "no dataset directory given");
  namespace fs = std::filesystem;
  std::set<std::string> seen_dirs;
  std::map<std::string, std::string> file_dir;  // scene file name -> the directory listing it
  std::vector<std::string> scenarios;
  DatasetSplit out;
  size_t sampled_from = 0;
  for (size_t d = 0; d < dirs.size(); ++d) {
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(dirs[d], ec);
    if (!seen_dirs.insert(ec ? dirs[d] : canonical.string()).second) {
      throw ValueError("data", dirs[d] + " is named twice");
    }
    DatasetSplit part = read_dataset_split(dirs[d], split);
    sampled_from += part.items.size();
    if (max_scenes > 0) part = evenly_spaced_sample(part, max_scenes);
    out.dir += (d ? ", " : "") + part.dir;
    out.split = part.split;
    if (std::find(scenarios.begin(), scenarios.end(), part.scenario) == scenarios.end())
      scenarios.push_back(part.scenario);
    for (DatasetItem& item : part.items) {
      const auto [it, fresh] = file_dir.emplace(item.file, part.dir);
      if (!fresh) {
        throw ValueError("data", "scene file " + item.file + " is in both " + it->second + " and " +
                                     part.dir +
                                     " (scenes of one evaluation need distinct file names)");
      }
      out.items.push_back(std::move(item));
    }
  }
  for (size_t i = 0; i < scenarios.size(); ++i) out.scenario += (i ? ", " : "") + scenarios[i];
  if (dirs.size() > 1 && out.items.size() < sampled_from) {
    out.split = split + ", " + std::to_string(out.items.size()) + " of " +
                std::to_string(sampled_from) + " evenly spaced per directory";
  }
  return out;
}

}  // namespace dynscope
