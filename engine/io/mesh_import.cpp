// Mesh import through assimp: bound what a file may cost, then triangulate, bake node transforms,
// merge, weld by position, and validate what the importer returned.
#include "engine/io/mesh_import.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "engine/core/error.h"

namespace dynscope {
namespace {

// What importing one element costs at most, in bytes: assimp's own copy (PLY keeps every property
// of every element as a separate value), its post-processing copies, and our welding map. Used
// only to refuse declared counts that cannot fit in the ceiling, so generous is safe.
constexpr uint64_t kBytesPerVertex = 256;
constexpr uint64_t kBytesPerFace = 128;
constexpr uint64_t kBytesPerPlyProperty = 48;
// Headers are short; a declaration further in than this is not looked for.
constexpr size_t kHeaderBytes = 64 * 1024;

std::string mib_text(uint64_t bytes) {
  std::ostringstream out;
  out.precision(3);
  out << static_cast<double>(bytes) / (1024.0 * 1024.0) << " MiB";
  return out.str();
}

std::string read_head(const std::string& path, size_t limit) {
  std::ifstream in(path, std::ios::binary);
  std::string head(limit, '\0');
  in.read(head.data(), static_cast<std::streamsize>(limit));
  head.resize(static_cast<size_t>(in.gcount()));
  return head;
}

// Parses a non-negative decimal count; false if `token` is not one or has more than 19 digits.
bool parse_count(const std::string& token, uint64_t* out) {
  if (token.empty() || token.size() > 19) return false;
  uint64_t v = 0;
  for (char c : token) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + static_cast<uint64_t>(c - '0');
  }
  *out = v;
  return true;
}

// a * b, saturating instead of wrapping.
uint64_t saturating_mul(uint64_t a, uint64_t b) {
  if (a != 0 && b > std::numeric_limits<uint64_t>::max() / a) {
    return std::numeric_limits<uint64_t>::max();
  }
  return a * b;
}

uint64_t saturating_add(uint64_t a, uint64_t b) {
  return b > std::numeric_limits<uint64_t>::max() - a ? std::numeric_limits<uint64_t>::max()
                                                      : a + b;
}

// Declared element counts of a file header and what they imply, for the checks below.
struct Declared {
  uint64_t min_body_bytes = 0;  // the fewest bytes after the header that can hold the elements
  uint64_t memory_bytes = 0;    // what importing them costs (kBytesPer*)
  std::string what;             // "8 vertices, 6 faces"
};

// OFF: a keyword ending in "OFF" (OFF, COFF, NOFF, STOFF, ...), then "vertices faces edges";
// '#' starts a comment. Each vertex is at least three one-character numbers and two separators.
bool declared_off(const std::string& head, Declared* out, uint64_t* header_end) {
  size_t pos = 0;
  std::vector<std::string> tokens;
  while (pos < head.size() && tokens.size() < 4) {
    const char c = head[pos];
    if (c == '#') {
      while (pos < head.size() && head[pos] != '\n') ++pos;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++pos;
    } else {
      const size_t start = pos;
      while (pos < head.size() && !std::isspace(static_cast<unsigned char>(head[pos])) &&
             head[pos] != '#') {
        ++pos;
      }
      tokens.push_back(head.substr(start, pos - start));
    }
  }
  if (tokens.size() < 3) return false;
  const std::string& key = tokens[0];
  if (key.size() < 3 || key.compare(key.size() - 3, 3, "OFF") != 0) return false;
  uint64_t vertices = 0, faces = 0;
  if (!parse_count(tokens[1], &vertices) || !parse_count(tokens[2], &faces)) return false;
  out->min_body_bytes = saturating_add(saturating_mul(vertices, 5), faces);
  out->memory_bytes = saturating_add(saturating_mul(vertices, kBytesPerVertex),
                                     saturating_mul(faces, kBytesPerFace));
  out->what = std::to_string(vertices) + " vertices, " + std::to_string(faces) + " faces";
  *header_end = pos;
  return true;
}

// Bytes of a PLY scalar type name, 0 if unknown.
uint64_t ply_type_bytes(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" ||
      type == "float32") {
    return 4;
  }
  if (type == "double" || type == "float64") return 8;
  return 0;
}

// PLY: "ply", "format ascii|binary_*", then "element NAME COUNT" followed by its "property"
// lines, up to "end_header". The fewest bytes an element takes: in ASCII one character and one
// separator per property; in binary the sum of its scalar sizes (a list at least its count).
bool declared_ply(const std::string& path, const std::string& head, Declared* out,
                  uint64_t* header_end) {
  if (head.compare(0, 4, "ply\n") != 0 && head.compare(0, 5, "ply\r\n") != 0) return false;
  const size_t end = head.find("end_header");
  // assimp's PLY reader can loop forever on a header cut short.
  if (end == std::string::npos) {
    throw IoError(path, "PLY header without end_header in its first " +
                            std::to_string(kHeaderBytes / 1024) + " KiB (truncated or corrupt)");
  }
  std::istringstream lines(head.substr(0, end));
  std::string line;
  bool ascii = true;
  uint64_t count = 0, min_bytes = 0, properties = 0;
  uint64_t total_elements = 0;
  auto close_element = [&] {
    out->min_body_bytes = saturating_add(out->min_body_bytes, saturating_mul(count, min_bytes));
    out->memory_bytes = saturating_add(
        out->memory_bytes,
        saturating_mul(count, saturating_add(kBytesPerFace,
                                             saturating_mul(properties, kBytesPerPlyProperty))));
    total_elements = saturating_add(total_elements, count);
    count = min_bytes = properties = 0;
  };
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (word == "format") {
      std::string kind;
      words >> kind;
      ascii = kind == "ascii";
    } else if (word == "element") {
      close_element();
      std::string name, number;
      words >> name >> number;
      if (!parse_count(number, &count)) return false;
    } else if (word == "property") {
      std::string type;
      words >> type;
      if (type == "list") words >> type;  // a list starts with its count
      ++properties;
      min_bytes += ascii ? 2 : ply_type_bytes(type);
    }
  }
  close_element();
  out->what = std::to_string(total_elements) + " elements";
  uint64_t after = end + std::string("end_header").size();
  if (after < head.size() && head[after] == '\r') ++after;
  if (after < head.size() && head[after] == '\n') ++after;
  *header_end = after;
  return true;
}

// Refuses a file before assimp reads it when it is larger than the ceiling, or when its header
// declares more elements than the rest of the file can hold or than the ceiling allows (assimp's
// OFF and PLY readers reserve the declared counts up front).
void check_declared_size(const std::string& path, const MeshImportOptions& options) {
  std::error_code ec;
  const uint64_t file_bytes = std::filesystem::file_size(path, ec);
  if (ec) throw IoError(path, "cannot read its size: " + ec.message());
  if (file_bytes > options.max_memory_bytes) {
    throw IoError(path, "is " + mib_text(file_bytes) + ", more than the mesh import limit of " +
                            mib_text(options.max_memory_bytes));
  }
  const std::string head = read_head(path, kHeaderBytes);
  Declared declared;
  uint64_t header_end = 0;
  if (!declared_off(head, &declared, &header_end) &&
      !declared_ply(path, head, &declared, &header_end)) {
    return;
  }
  const uint64_t body = file_bytes - std::min<uint64_t>(header_end, file_bytes);
  if (declared.min_body_bytes > body) {
    throw IoError(path, "header declares " + declared.what + ", which need at least " +
                            std::to_string(declared.min_body_bytes) + " bytes, but only " +
                            std::to_string(body) + " follow (corrupt or truncated)");
  }
  if (declared.memory_bytes > options.max_memory_bytes) {
    throw IoError(path, "header declares " + declared.what +
                            ", more than the mesh import limit "
                            "of " +
                            mib_text(options.max_memory_bytes) + " allows");
  }
}

// Vertices the scene has once every node's meshes are instanced (what PreTransformVertices will
// allocate), saturating; nodes beyond `max_nodes` count as over any limit.
uint64_t instanced_vertices(const aiScene& scene, uint64_t max_nodes) {
  if (scene.mRootNode == nullptr) return 0;
  std::vector<const aiNode*> stack{scene.mRootNode};
  uint64_t total = 0, visited = 0;
  while (!stack.empty()) {
    const aiNode* node = stack.back();
    stack.pop_back();
    if (node == nullptr) continue;
    if (++visited > max_nodes) return std::numeric_limits<uint64_t>::max();
    for (unsigned i = 0; node->mMeshes != nullptr && i < node->mNumMeshes; ++i) {
      const unsigned m = node->mMeshes[i];
      if (m < scene.mNumMeshes) total = saturating_add(total, scene.mMeshes[m]->mNumVertices);
    }
    for (unsigned c = 0; node->mChildren != nullptr && c < node->mNumChildren; ++c) {
      stack.push_back(node->mChildren[c]);
    }
  }
  return total;
}

// Checks every pointer and index the merge below follows (ValidateDataStructure checks them too;
// this keeps the merge safe whatever the importer returns).
void validate_meshes(const std::string& path, const aiScene& scene) {
  if (scene.mNumMeshes > 0 && scene.mMeshes == nullptr) throw IoError(path, "mesh list missing");
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    const std::string where = "mesh " + std::to_string(m);
    if (mesh == nullptr) throw IoError(path, where + " missing");
    if ((mesh->mNumVertices > 0 && mesh->mVertices == nullptr) ||
        (mesh->mNumFaces > 0 && mesh->mFaces == nullptr)) {
      throw IoError(path, where + ": vertex or face array missing");
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices > 0 && face.mIndices == nullptr) {
        throw IoError(path, where + ": face " + std::to_string(f) + " has no index array");
      }
      for (unsigned i = 0; i < face.mNumIndices; ++i) {
        if (face.mIndices[i] >= mesh->mNumVertices) {
          throw IoError(path, where + ": face " + std::to_string(f) + " uses vertex " +
                                  std::to_string(face.mIndices[i]) + ", but the mesh has " +
                                  std::to_string(mesh->mNumVertices));
        }
      }
    }
  }
}

struct PositionHash {
  size_t operator()(const Vec3& p) const {
    size_t h = 0;
    for (int i = 0; i < 3; ++i) {
      // +0.0 so that -0.0 and 0.0 hash alike (they compare equal).
      h = h * 1000003u ^ std::hash<double>()(p[i] + 0.0);
    }
    return h;
  }
};

struct PositionEqual {
  bool operator()(const Vec3& a, const Vec3& b) const { return a == b; }
};

}  // namespace

bool is_mesh_file(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext.size() < 2) return false;
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  Assimp::Importer importer;
  return importer.IsExtensionSupported(ext.c_str());
}

namespace {

// The whole import in this process: bounds, assimp, validation, merge and weld.
Mesh import_in_process(const std::string& path, const MeshImportOptions& options) {
  check_declared_size(path, options);
  Assimp::Importer importer;
  // Points and lines are sorted into their own meshes and then removed: only surfaces matter.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Node transforms are baked in a second step, once the instanced size is known to fit.
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                  aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (scene == nullptr) throw IoError(path, std::string("assimp: ") + importer.GetErrorString());
  validate_meshes(path, *scene);
  const uint64_t max_vertices = options.max_memory_bytes / kBytesPerVertex;
  if (instanced_vertices(*scene, max_vertices) > max_vertices) {
    throw IoError(path, "its node hierarchy instances more than " + std::to_string(max_vertices) +
                            " vertices, more than the mesh import limit of " +
                            mib_text(options.max_memory_bytes) + " allows");
  }
  scene = importer.ApplyPostProcessing(aiProcess_PreTransformVertices);
  if (scene == nullptr) throw IoError(path, std::string("assimp: ") + importer.GetErrorString());
  validate_meshes(path, *scene);

  // One mesh for the whole file. Vertices are welded by exact position across all meshes
  // (assimp joins only within a mesh and keeps copies that differ in normals or UVs, e.g. STL's
  // per-face normals), so shared corners become shared vertices.
  std::unordered_map<Vec3, int32_t, PositionHash, PositionEqual> index_of;
  std::vector<Vec3> vertices;
  std::vector<Eigen::Matrix<int32_t, 1, 3>> faces;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    std::vector<int32_t> remap(mesh->mNumVertices);
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      const Vec3 q(p.x, p.y, p.z);
      const auto [it, inserted] = index_of.try_emplace(q, static_cast<int32_t>(vertices.size()));
      if (inserted) vertices.push_back(q);
      remap[v] = it->second;
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      const Eigen::Matrix<int32_t, 1, 3> tri(remap[face.mIndices[0]], remap[face.mIndices[1]],
                                             remap[face.mIndices[2]]);
      // Welding can collapse a sliver triangle onto an edge; it has no area to keep.
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
      faces.push_back(tri);
    }
  }
  if (faces.empty()) throw IoError(path, "contains no triangles");

  // Vertices used by no kept triangle (from dropped points/lines) are removed; the others keep
  // their order.
  std::vector<int32_t> compact(vertices.size(), -1);
  for (const auto& tri : faces) {
    for (int c = 0; c < 3; ++c) compact[static_cast<size_t>(tri[c])] = 0;
  }
  Mesh out;
  int32_t used = 0;
  for (int32_t& k : compact) {
    if (k == 0) k = used++;
  }
  out.vertices.resize(used, 3);
  for (size_t v = 0; v < vertices.size(); ++v) {
    if (compact[v] >= 0) out.vertices.row(compact[v]) = vertices[v].transpose();
  }
  out.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int c = 0; c < 3; ++c) {
      out.faces(static_cast<Eigen::Index>(f), c) = compact[static_cast<size_t>(faces[f][c])];
    }
  }
  if (!out.vertices.allFinite()) throw IoError(path, "contains non-finite vertex coordinates");
  return out;
}

// Writes all of `size` bytes to `fd` (a pipe), retrying short writes.
bool write_all(int fd, const void* data, size_t size) {
  const auto* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

// Bytes of this process's address space (the first field of /proc/self/statm, in pages).
uint64_t address_space_bytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t pages = 0;
  statm >> pages;
  return pages * static_cast<uint64_t>(sysconf(_SC_PAGESIZE));
}

// The child's side: import, then send [status byte][payload] through `fd`. Status 0: vertex and
// face counts (uint64 each), vertices (doubles) and faces (int32); status 1: the error message.
[[noreturn]] void import_in_child(int fd, const std::string& path,
                                  const MeshImportOptions& options) {
  // The importer's own diagnostics (assertion texts) must not reach the parent's terminal.
  const int null_fd = open("/dev/null", O_WRONLY);
  if (null_fd >= 0) {
    dup2(null_fd, 1);
    dup2(null_fd, 2);
  }
  // The ceiling is enforced on top of what the process already maps (libraries, the parent's
  // heap): an allocation past it fails with bad_alloc instead of exhausting the machine.
  const uint64_t limit = address_space_bytes() + options.max_memory_bytes;
  const rlimit as_limit{limit, limit};
  setrlimit(RLIMIT_AS, &as_limit);
  std::string message;
  try {
    const Mesh mesh = import_in_process(path, options);
    const uint64_t counts[2] = {static_cast<uint64_t>(mesh.vertices.rows()),
                                static_cast<uint64_t>(mesh.faces.rows())};
    const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> v = mesh.vertices;
    const Eigen::Matrix<int32_t, Eigen::Dynamic, 3, Eigen::RowMajor> f = mesh.faces;
    const char ok = 0;
    const bool sent = write_all(fd, &ok, 1) && write_all(fd, counts, sizeof counts) &&
                      write_all(fd, v.data(), sizeof(double) * static_cast<size_t>(v.size())) &&
                      write_all(fd, f.data(), sizeof(int32_t) * static_cast<size_t>(f.size()));
    _exit(sent ? 0 : 1);
  } catch (const IoError& e) {
    // The parent names the file itself.
    message = e.what();
    const std::string prefix = path + ": ";
    if (message.compare(0, prefix.size(), prefix) == 0) message.erase(0, prefix.size());
  } catch (const std::bad_alloc&) {
    message =
        "needs more memory than the mesh import limit of " + mib_text(options.max_memory_bytes);
  } catch (const std::exception& e) {
    message = e.what();
  }
  const char failed = 1;
  write_all(fd, &failed, 1);
  write_all(fd, message.data(), message.size());
  _exit(0);
}

// Reads everything the child sends until it closes the pipe or `deadline` passes; false on
// timeout.
bool read_until_closed(int fd, std::string* out, std::chrono::steady_clock::time_point deadline) {
  char buf[1 << 16];
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd p{fd, POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>(std::min<int64_t>(left.count(), 1000)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;
    const ssize_t n = read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return true;
    out->append(buf, static_cast<size_t>(n));
  }
}

// Runs import_in_process in a child process: a crash, a hang or a runaway allocation inside the
// importer (assimp asserts and segfaults on some corrupt files) ends the child, never the caller.
Mesh import_isolated(const std::string& path, const MeshImportOptions& options) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    throw IoError(path, std::string("cannot start the import process: ") + std::strerror(errno));
  }
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    throw IoError(path, std::string("cannot start the import process: ") + std::strerror(errno));
  }
  if (pid == 0) {
    close(fds[0]);
    import_in_child(fds[1], path, options);
  }
  close(fds[1]);
  std::string reply;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(options.max_seconds));
  const bool finished = read_until_closed(fds[0], &reply, deadline);
  close(fds[0]);
  if (!finished) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!finished) {
    char limit[32];
    std::snprintf(limit, sizeof limit, "%g", options.max_seconds);
    throw IoError(
        path, std::string("the importer did not finish within ") + limit + " s (corrupt file?)");
  }
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    throw IoError(path, std::string("the importer crashed on this file (signal ") +
                            std::to_string(sig) + ", " + strsignal(sig) +
                            "): corrupt or unsupported");
  }
  if (reply.empty()) throw IoError(path, "the import process ended without a result");
  if (reply[0] != 0) throw IoError(path, reply.substr(1));
  uint64_t counts[2] = {0, 0};
  if (reply.size() < 1 + sizeof counts) throw IoError(path, "incomplete result of the import");
  std::memcpy(counts, reply.data() + 1, sizeof counts);
  const size_t vertex_bytes = sizeof(double) * 3 * counts[0];
  const size_t face_bytes = sizeof(int32_t) * 3 * counts[1];
  if (reply.size() != 1 + sizeof counts + vertex_bytes + face_bytes) {
    throw IoError(path, "incomplete result of the import");
  }
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> v(counts[0], 3);
  Eigen::Matrix<int32_t, Eigen::Dynamic, 3, Eigen::RowMajor> f(counts[1], 3);
  std::memcpy(v.data(), reply.data() + 1 + sizeof counts, vertex_bytes);
  std::memcpy(f.data(), reply.data() + 1 + sizeof counts + vertex_bytes, face_bytes);
  Mesh mesh;
  mesh.vertices = v;
  mesh.faces = f;
  return mesh;
}

}  // namespace

Mesh import_mesh(const std::string& path, const MeshImportOptions& options) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw IoError(path, "no such file");
  if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "not a regular file");
  return options.isolate ? import_isolated(path, options) : import_in_process(path, options);
}

}  // namespace dynscope
