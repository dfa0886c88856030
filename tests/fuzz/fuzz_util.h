// Helpers of the fuzz suite: run the built binary under a time limit with its peak memory, and
// the structured mutations of HDF5, JSON and plain files that the suite feeds it.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace dynscope::fuzz {

/// How one run of the binary ended.
struct RunResult {
  int exit_code = -1;  ///< Exit status, or -1 if it did not exit normally.
  int signal = 0;      ///< Signal that ended it (SIGKILL after a timeout), 0 if none.
  bool timed_out = false;
  long max_rss_kb = 0;  ///< Peak resident memory of the process.
  std::string output;   ///< stdout and stderr together.
};

/// Runs `DYNSCOPE_BINARY args...` (no shell) with stdout and stderr into `log`, killed after
/// `timeout_s` seconds.
inline RunResult run_binary(const std::vector<std::string>& args, const std::string& log,
                            double timeout_s) {
  RunResult r;
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    std::vector<char*> argv;
    std::string binary = DYNSCOPE_BINARY;
    argv.push_back(binary.data());
    std::vector<std::string> copy = args;
    for (std::string& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(binary.c_str(), argv.data());
    _exit(127);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  int status = 0;
  struct rusage usage {};
  while (true) {
    const pid_t done = wait4(pid, &status, WNOHANG, &usage);
    if (done == pid) break;
    if (std::chrono::steady_clock::now() > deadline) {
      r.timed_out = true;
      kill(pid, SIGKILL);
      wait4(pid, &status, 0, &usage);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  r.max_rss_kb = usage.ru_maxrss;
  std::ifstream in(log, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  r.output = ss.str();
  return r;
}

/// Bytes of a file ("" if it does not exist).
inline std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

/// One mutated input: a name for failure messages and a function that turns a copy of the
/// original file (at the given path) into the mutant.
struct Mutation {
  std::string name;
  std::function<void(const std::string& path)> apply;
};

/// Deterministic 64-bit generator (splitmix64) for bit positions and values.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }

 private:
  uint64_t state_;
};

/// Byte-level mutations of any file: truncations at `cuts` fractions, `flips` single bit flips
/// at seeded offsets, and zeroed 64-byte blocks at `blocks` offsets.
inline std::vector<Mutation> byte_mutations(size_t size, int cuts, int flips, int blocks,
                                            uint64_t seed) {
  std::vector<Mutation> out;
  for (int i = 0; i < cuts; ++i) {
    const size_t keep = size * static_cast<size_t>(i) / static_cast<size_t>(cuts);
    out.push_back({"truncated to " + std::to_string(keep) + " bytes",
                   [keep](const std::string& p) { std::filesystem::resize_file(p, keep); }});
  }
  Random rng(seed);
  for (int i = 0; i < flips; ++i) {
    const size_t at = static_cast<size_t>(rng.next() % size);
    const int bit = static_cast<int>(rng.next() % 8);
    out.push_back({"bit " + std::to_string(bit) + " of byte " + std::to_string(at) + " flipped",
                   [at, bit](const std::string& p) {
                     std::string b = read_bytes(p);
                     b[at] = static_cast<char>(b[at] ^ (1 << bit));
                     write_bytes(p, b);
                   }});
  }
  for (int i = 0; i < blocks; ++i) {
    const size_t at = static_cast<size_t>(rng.next() % size);
    out.push_back({"64 bytes zeroed at " + std::to_string(at), [at](const std::string& p) {
                     std::string b = read_bytes(p);
                     for (size_t k = at; k < std::min(b.size(), at + 64); ++k) b[k] = 0;
                     write_bytes(p, b);
                   }});
  }
  return out;
}

/// Objects (groups and datasets, by path without the leading slash) and attributes of an HDF5
/// file.
struct H5Contents {
  std::vector<std::string> groups, datasets;
  std::vector<std::pair<std::string, std::string>> attributes;  ///< (object path, name)
};

inline H5Contents list_h5(const std::string& path) {
  H5Contents c;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  auto visit = [](hid_t obj, const char* name, const H5O_info_t* info, void* data) -> herr_t {
    auto* contents = static_cast<H5Contents*>(data);
    const std::string n = name;
    if (info->type == H5O_TYPE_GROUP && n != ".") contents->groups.push_back(n);
    if (info->type == H5O_TYPE_DATASET) contents->datasets.push_back(n);
    const hid_t o = H5Oopen(obj, name, H5P_DEFAULT);
    auto attr = [](hid_t, const char* attr_name, const H5A_info_t*, void* d) -> herr_t {
      auto* p = static_cast<std::pair<H5Contents*, std::string>*>(d);
      p->first->attributes.emplace_back(p->second, attr_name);
      return 0;
    };
    std::pair<H5Contents*, std::string> ctx{contents, n == "." ? "" : n};
    hsize_t idx = 0;
    H5Aiterate2(o, H5_INDEX_NAME, H5_ITER_INC, &idx, attr, &ctx);
    H5Oclose(o);
    return 0;
  };
  H5Ovisit(file, H5_INDEX_NAME, H5_ITER_INC, visit, &c);
  H5Fclose(file);
  return c;
}

/// Opens `path` read-write, runs `edit` on the file id, closes it.
inline void edit_h5(const std::string& path, const std::function<void(hid_t)>& edit) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return;
  edit(file);
  H5Fclose(file);
}

/// Replaces dataset `name` by one of `dims` float64 filled with `value` (written unless
/// `unwritten`, which leaves a declared-only dataset of any size).
inline void replace_dataset(hid_t file, const std::string& name, const std::vector<hsize_t>& dims,
                            double value, bool unwritten = false) {
  H5Ldelete(file, name.c_str(), H5P_DEFAULT);
  const hid_t space = dims.empty()
                          ? H5Screate(H5S_SCALAR)
                          : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  const hid_t ds =
      H5Dcreate2(file, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (!unwritten) {
    size_t n = 1;
    for (hsize_t d : dims) n *= static_cast<size_t>(d);
    std::vector<double> values(n, value);
    if (n > 0) H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  }
  H5Dclose(ds);
  H5Sclose(space);
}

/// Dims of dataset `name`.
inline std::vector<hsize_t> dataset_dims(hid_t file, const std::string& name) {
  const hid_t ds = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  const hid_t space = H5Dget_space(ds);
  std::vector<hsize_t> dims(static_cast<size_t>(std::max(0, H5Sget_simple_extent_ndims(space))));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  H5Sclose(space);
  H5Dclose(ds);
  return dims;
}

/// Replaces dataset `name` by a string dataset of the same first extent.
inline void replace_with_strings(hid_t file, const std::string& name) {
  const std::vector<hsize_t> dims = dataset_dims(file, name);
  H5Ldelete(file, name.c_str(), H5P_DEFAULT);
  const hsize_t n = dims.empty() ? 1 : dims[0];
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, 4);
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t ds =
      H5Dcreate2(file, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  std::vector<char> text(static_cast<size_t>(n) * 4, 'x');
  H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, text.data());
  H5Dclose(ds);
  H5Sclose(space);
  H5Tclose(type);
}

/// Replaces attribute `name` of object `object` ("" = root) by a float64 scalar `value`, or by a
/// string when `text` is given.
inline void replace_attribute(hid_t file, const std::string& object, const std::string& name,
                              double value, const char* text = nullptr) {
  const hid_t o = H5Oopen(file, object.empty() ? "/" : object.c_str(), H5P_DEFAULT);
  H5Adelete(o, name.c_str());
  const hid_t space = H5Screate(H5S_SCALAR);
  if (text != nullptr) {
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, std::max<size_t>(1, std::strlen(text)));
    const hid_t a = H5Acreate2(o, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, type, text);
    H5Aclose(a);
    H5Tclose(type);
  } else {
    const hid_t a = H5Acreate2(o, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_DOUBLE, &value);
    H5Aclose(a);
  }
  H5Sclose(space);
  H5Oclose(o);
}

/// "frames/0007/objects/positions" → "frames/N/objects/positions", "vertices_3" → "vertices_N":
/// mutations are applied to the first few paths of each pattern only.
inline std::string path_pattern(const std::string& path) {
  std::string out;
  for (size_t i = 0; i < path.size(); ++i) {
    if (std::isdigit(static_cast<unsigned char>(path[i]))) {
      out += 'N';
      while (i + 1 < path.size() && std::isdigit(static_cast<unsigned char>(path[i + 1]))) ++i;
    } else {
      out += path[i];
    }
  }
  return out;
}

}  // namespace dynscope::fuzz
