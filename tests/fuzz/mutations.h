// Structured mutations shared by the fuzz suites (the binary's and the viewer's): HDF5 files
// (groups, datasets, attributes, link names), JSON documents and meshes.
#pragma once

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "tests/fuzz/fuzz_util.h"

namespace dynscope::fuzz {

// Mutations per test by default: every run starts the whole binary (about a second of CPU), and
// the suite must stay within a few minutes on two cores. DYNSCOPE_FUZZ_MUTATIONS raises it for a
// deeper run; the sample is spread evenly over the full list, so every kind of mutation is hit.
inline size_t mutation_budget() {
  const char* env = std::getenv("DYNSCOPE_FUZZ_MUTATIONS");
  return env != nullptr ? static_cast<size_t>(std::strtoull(env, nullptr, 10)) : 28;
}

inline std::vector<Mutation> sample(const std::vector<Mutation>& all, size_t budget) {
  if (all.size() <= budget) return all;
  std::vector<Mutation> out;
  for (size_t i = 0; i < budget; ++i) out.push_back(all[i * all.size() / budget]);
  return out;
}

// Structured mutations of an HDF5 file: every group and dataset deleted, datasets with NaN,
// inf, huge or negative values, another type, one row short or long, a huge declared shape;
// every attribute deleted or replaced by NaN, -1, a huge value or a string; then truncations,
// bit flips and zeroed blocks. Paths differing only in numbers (frames/0003, vertices_2) are
// mutated for the first `per_pattern` of them.
inline std::vector<Mutation> h5_mutations(const std::string& path, int per_pattern, uint64_t seed) {
  const H5Contents c = list_h5(path);
  std::map<std::string, int> seen;
  auto take = [&](const std::string& p, const char* kind) {
    return seen[std::string(kind) + path_pattern(p)]++ < per_pattern;
  };
  std::vector<Mutation> out;
  for (const std::string& g : c.groups) {
    if (!take(g, "g")) continue;
    out.push_back({"group " + g + " deleted", [g](const std::string& p) {
                     edit_h5(p, [&](hid_t f) { H5Ldelete(f, g.c_str(), H5P_DEFAULT); });
                   }});
  }
  for (const std::string& d : c.datasets) {
    if (!take(d, "d")) continue;
    out.push_back({"dataset " + d + " deleted", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) { H5Ldelete(f, d.c_str(), H5P_DEFAULT); });
                   }});
    for (double v : {std::nan(""), static_cast<double>(INFINITY), 1e300, -1.0, 3.7}) {
      out.push_back(
          {"dataset " + d + " filled with " + std::to_string(v), [d, v](const std::string& p) {
             edit_h5(p, [&](hid_t f) { replace_dataset(f, d, dataset_dims(f, d), v); });
           }});
    }
    out.push_back({"dataset " + d + " as strings", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) { replace_with_strings(f, d); });
                   }});
    out.push_back({"dataset " + d + " one row short", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) {
                       std::vector<hsize_t> dims = dataset_dims(f, d);
                       if (!dims.empty() && dims[0] > 0) --dims[0];
                       replace_dataset(f, d, dims, 0.5);
                     });
                   }});
    out.push_back({"dataset " + d + " one column more", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) {
                       std::vector<hsize_t> dims = dataset_dims(f, d);
                       if (dims.empty()) dims.push_back(1);
                       ++dims.back();
                       replace_dataset(f, d, dims, 0.5);
                     });
                   }});
    out.push_back({"dataset " + d + " declares 10^9 rows", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) {
                       std::vector<hsize_t> dims = dataset_dims(f, d);
                       if (dims.empty()) dims.push_back(1);
                       dims[0] = 1000000000;
                       replace_dataset(f, d, dims, 0.0, /*unwritten=*/true);
                     });
                   }});
  }
  for (const auto& [object, name] : c.attributes) {
    if (!take(object + "@" + name, "a")) continue;
    const std::string label = "attribute " + object + "@" + name;
    out.push_back({label + " deleted", [object = object, name = name](const std::string& p) {
                     edit_h5(p, [&](hid_t f) {
                       const hid_t o =
                           H5Oopen(f, object.empty() ? "/" : object.c_str(), H5P_DEFAULT);
                       H5Adelete(o, name.c_str());
                       H5Oclose(o);
                     });
                   }});
    for (double v : {std::nan(""), -1.0, 1e12, 1e300}) {
      out.push_back({label + " = " + std::to_string(v),
                     [object = object, name = name, v](const std::string& p) {
                       edit_h5(p, [&](hid_t f) { replace_attribute(f, object, name, v); });
                     }});
    }
    out.push_back({label + " = 'x'", [object = object, name = name](const std::string& p) {
                     edit_h5(p, [&](hid_t f) { replace_attribute(f, object, name, 0, "x"); });
                   }});
  }
  const std::vector<Mutation> bytes =
      byte_mutations(static_cast<size_t>(std::filesystem::file_size(path)), 8, 24, 6, seed);
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

// Structured mutations of a JSON document: every member deleted or replaced by -1, 3.7, 1e300,
// 1e12, a string, null or an empty array; then truncations.
inline std::vector<Mutation> json_mutations(const std::string& path) {
  const nlohmann::json doc = nlohmann::json::parse(read_bytes(path));
  std::vector<nlohmann::json::json_pointer> pointers;
  std::function<void(const nlohmann::json&, const nlohmann::json::json_pointer&)> walk =
      [&](const nlohmann::json& j, const nlohmann::json::json_pointer& at) {
        if (!at.empty()) pointers.push_back(at);
        if (j.is_object()) {
          for (auto it = j.begin(); it != j.end(); ++it) walk(it.value(), at / it.key());
        } else if (j.is_array()) {
          for (size_t i = 0; i < j.size() && i < 3; ++i) walk(j[i], at / i);
        }
      };
  walk(doc, nlohmann::json::json_pointer());
  std::vector<Mutation> out;
  const std::vector<std::pair<std::string, nlohmann::json>> values = {
      {"-1", -1},
      {"3.7", 3.7},
      {"1e300", 1e300},
      {"1e12", 1e12},
      {"'x'", "x"},
      {"null", nullptr},
      {"[]", nlohmann::json::array()}};
  for (const nlohmann::json::json_pointer& p : pointers) {
    out.push_back({p.to_string() + " deleted", [doc, p](const std::string& file) {
                     nlohmann::json j = doc;
                     nlohmann::json& parent = j.at(p.parent_pointer());
                     if (parent.is_array()) {
                       parent.erase(static_cast<size_t>(std::stoul(p.back())));
                     } else {
                       parent.erase(p.back());
                     }
                     write_bytes(file, j.dump(2));
                   }});
    if (!doc.at(p).is_primitive()) continue;
    for (const auto& [label, value] : values) {
      out.push_back({p.to_string() + " = " + label, [doc, p, value = value](const std::string& f) {
                       nlohmann::json j = doc;
                       j[p] = value;
                       write_bytes(f, j.dump(2));
                     }});
    }
  }
  const std::vector<Mutation> bytes =
      byte_mutations(static_cast<size_t>(std::filesystem::file_size(path)), 4, 0, 0, 1);
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

// The stored names of the links in /frames ("0000", "0001", ...) corrupted in place: their bytes
// (and the byte before, where a length or flags field sits) overwritten with 0xff, 0 or garbage.
inline std::vector<Mutation> link_name_mutations(const std::string& path) {
  const std::string bytes = read_bytes(path);
  std::vector<Mutation> out;
  for (const char* name : {"0000", "0001", "0013", "0023"}) {
    for (size_t at = bytes.find(name); at != std::string::npos && at > 0;
         at = bytes.find(name, at + 1)) {
      for (const auto& [label, fill] : std::vector<std::pair<std::string, std::string>>{
               {"0xff", "\xff\xff\xff\xff"}, {"zero", std::string(4, '\0')}, {"text", "a/.."}}) {
        out.push_back(
            {std::string("link name ") + name + " at " + std::to_string(at) + " -> " + label,
             [at, fill = fill](const std::string& p) {
               std::string b = read_bytes(p);
               b.replace(at, 4, fill);
               write_bytes(p, b);
             }});
      }
      out.push_back(
          {std::string("byte before link name ") + name + " at " + std::to_string(at) + " -> 0xff",
           [at](const std::string& p) {
             std::string b = read_bytes(p);
             b[at - 1] = static_cast<char>(0xff);
             write_bytes(p, b);
           }});
    }
  }
  return out;
}

// Small meshes of every text format, and a binary PLY.
inline std::vector<std::pair<std::string, std::string>> mesh_files() {
  std::string binary_ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n";
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  binary_ply.append(reinterpret_cast<const char*>(v), sizeof v);
  const unsigned char n = 3;
  const int32_t f[3] = {0, 1, 2};
  binary_ply.append(reinterpret_cast<const char*>(&n), 1);
  binary_ply.append(reinterpret_cast<const char*>(f), sizeof f);
  return {
      {"tetra.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"},
      {"tetra.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"},
      {"tetra.ply",
       "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
       "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
       "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"},
      {"binary.ply", binary_ply},
      {"tri.stl",
       "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
       "endloop\nendfacet\nendsolid t\n"},
  };
}

// Text mutations of a mesh: every number replaced by a huge count, a negative index, NaN or
// garbage, one at a time; then truncations and bit flips.
inline std::vector<Mutation> mesh_mutations(const std::string& text, uint64_t seed) {
  std::vector<Mutation> out;
  std::vector<std::pair<size_t, size_t>> numbers;  // (start, length) of each number token
  for (size_t i = 0; i < text.size();) {
    if (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '-') {
      size_t j = i;
      while (j < text.size() && !std::isspace(static_cast<unsigned char>(text[j]))) ++j;
      numbers.emplace_back(i, j - i);
      i = j;
    } else {
      ++i;
    }
  }
  for (size_t k = 0; k < numbers.size() && k < 40; ++k) {
    for (const char* value : {"353535235358", "-7", "nan", "2000000000", "1e39", "#"}) {
      const auto [start, length] = numbers[k];
      std::string mutated = text;
      mutated.replace(start, length, value);
      out.push_back({"number " + std::to_string(k) + " -> " + value,
                     [mutated](const std::string& p) { write_bytes(p, mutated); }});
    }
  }
  const std::vector<Mutation> bytes = byte_mutations(text.size(), 6, 12, 0, seed);
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

}  // namespace dynscope::fuzz
