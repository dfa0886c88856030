// HDF5 RAII handles and shape/type-checked dataset and attribute access.
#include "engine/io/h5_util.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <limits>

#include "engine/core/error.h"

namespace dynscope::h5 {
namespace {

herr_t keep_innermost(unsigned n, const H5E_error2_t* err, void* client) {
  auto* out = static_cast<std::string*>(client);
  if (n == 0 && err != nullptr && err->desc != nullptr) *out = err->desc;
  return 0;
}

std::string with_hdf5_reason(const std::string& message) {
  const std::string reason = take_error();
  return reason.empty() ? message : message + " (HDF5: " + reason + ")";
}

// A dataset or an attribute: both are read the same way except for the final call.
struct Source {
  hid_t id;
  bool attribute;
};

herr_t read_raw(const Source& src, hid_t mem_type, void* buffer) {
  return src.attribute ? H5Aread(src.id, mem_type, buffer)
                       : H5Dread(src.id, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer);
}

Handle space_of(const Source& src) {
  return Handle(src.attribute ? H5Aget_space(src.id) : H5Dget_space(src.id));
}

Handle type_of(const Source& src) {
  return Handle(src.attribute ? H5Aget_type(src.id) : H5Dget_type(src.id));
}

Shape shape_of(const Source& src) {
  Shape s;
  Handle space = space_of(src);
  Handle type = type_of(src);
  if (!space.valid() || !type.valid()) return s;
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank > 0) {
    s.dims.resize(static_cast<size_t>(rank));
    H5Sget_simple_extent_dims(space.get(), s.dims.data(), nullptr);
  }
  s.type_class = H5Tget_class(type.get());
  s.type_size = H5Tget_size(type.get());
  if (s.type_class == H5T_INTEGER) {
    s.is_signed = H5Tget_sign(type.get()) == H5T_SGN_2;
  } else if (s.type_class == H5T_ENUM) {
    Handle base(H5Tget_super(type.get()));
    s.is_signed = H5Tget_sign(base.get()) == H5T_SGN_2;
  }
  return s;
}

size_t element_count(const Shape& s) {
  size_t n = 1;
  for (hsize_t d : s.dims) n *= static_cast<size_t>(d);
  return n;
}

// Largest array one read may allocate, in bytes (numbers are read as 8-byte values).
constexpr uint64_t kMaxReadBytes = uint64_t{1} << 30;
// Deflate, HDF5's standard compression filter, shrinks data by at most this factor.
constexpr uint64_t kMaxCompressionRatio = 1032;

uint64_t saturating_mul(uint64_t a, uint64_t b) {
  if (a != 0 && b > std::numeric_limits<uint64_t>::max() / a) {
    return std::numeric_limits<uint64_t>::max();
  }
  return a * b;
}

// Refuses a read whose declared shape cannot be real: more bytes than the file (times the best
// compression ratio when the dataset is filtered) can hold, or more than one read may allocate.
// A corrupted dataspace otherwise makes the read allocate whatever the header says.
void check_declared_size(const Source& src, const Shape& s, const std::string& file,
                         const std::string& field) {
  uint64_t count = 1;
  for (hsize_t d : s.dims) count = saturating_mul(count, d);
  const uint64_t stored = saturating_mul(count, s.type_size);
  const uint64_t in_memory = saturating_mul(count, std::max<uint64_t>(8, s.type_size));
  std::error_code ec;
  const uint64_t file_bytes = std::filesystem::file_size(file, ec);
  if (ec) return;  // not a plain file on disk: nothing to compare with
  bool filtered = false;
  if (!src.attribute) {
    Handle dcpl(H5Dget_create_plist(src.id));
    filtered = dcpl.valid() && H5Pget_nfilters(dcpl.get()) > 0;
  }
  const uint64_t limit = filtered ? saturating_mul(file_bytes, kMaxCompressionRatio) : file_bytes;
  if (stored > limit) {
    throw FormatError(file, field,
                      "declares " + s.text() + " (" + std::to_string(stored) +
                          " bytes), more than the file of " + std::to_string(file_bytes) +
                          " bytes can hold (corrupt?)");
  }
  if (in_memory > kMaxReadBytes) {
    throw FormatError(file, field,
                      "declares " + s.text() + ", more than the read limit of " +
                          std::to_string(kMaxReadBytes >> 20) + " MiB");
  }
}

bool is_numeric(const Shape& s) {
  return s.type_class == H5T_INTEGER || s.type_class == H5T_FLOAT || s.type_class == H5T_ENUM;
}

bool is_integral(const Shape& s) { return s.type_class == H5T_INTEGER || s.type_class == H5T_ENUM; }

// Enums (h5py stores numpy bool as an int8 enum FALSE/TRUE) have no conversion path to plain
// numbers in HDF5, so they are read as their native base integer and decoded here.
std::vector<int64_t> read_enum(const Source& src, const Shape& s, const std::string& file,
                               const std::string& field) {
  check_declared_size(src, s, file, field);
  Handle file_type = type_of(src);
  Handle mem_type(H5Tget_native_type(file_type.get(), H5T_DIR_ASCEND));
  const size_t n = element_count(s);
  const size_t size = H5Tget_size(mem_type.get());
  std::vector<unsigned char> raw(n * size);
  if (n > 0 && read_raw(src, mem_type.get(), raw.data()) < 0) {
    throw FormatError(file, field, with_hdf5_reason("read failed"));
  }
  std::vector<int64_t> out(n);
  for (size_t i = 0; i < n; ++i) {
    const unsigned char* p = raw.data() + i * size;
    switch (size) {
      case 1:
        out[i] = s.is_signed ? *reinterpret_cast<const int8_t*>(p) : *p;
        break;
      case 2: {
        int16_t v;
        std::memcpy(&v, p, 2);
        out[i] = s.is_signed ? v : static_cast<uint16_t>(v);
        break;
      }
      case 4: {
        int32_t v;
        std::memcpy(&v, p, 4);
        out[i] = s.is_signed ? v : static_cast<uint32_t>(v);
        break;
      }
      case 8:
        std::memcpy(&out[i], p, 8);
        break;
      default:
        throw FormatError(file, field, "unsupported enum size " + std::to_string(size));
    }
  }
  return out;
}

std::vector<double> read_doubles(const Source& src, const Shape& s, const std::string& file,
                                 const std::string& field) {
  if (!is_numeric(s)) throw FormatError(file, field, "expected numbers, got " + s.text());
  if (s.type_class == H5T_ENUM) {
    const std::vector<int64_t> ints = read_enum(src, s, file, field);
    return std::vector<double>(ints.begin(), ints.end());
  }
  check_declared_size(src, s, file, field);
  std::vector<double> out(element_count(s));
  if (!out.empty() && read_raw(src, H5T_NATIVE_DOUBLE, out.data()) < 0) {
    throw FormatError(file, field, with_hdf5_reason("read failed"));
  }
  return out;
}

std::vector<int64_t> read_ints(const Source& src, const Shape& s, const std::string& file,
                               const std::string& field) {
  if (!is_integral(s)) throw FormatError(file, field, "expected integers, got " + s.text());
  if (s.type_class == H5T_ENUM) return read_enum(src, s, file, field);
  check_declared_size(src, s, file, field);
  std::vector<int64_t> out(element_count(s));
  if (!out.empty() && read_raw(src, H5T_NATIVE_INT64, out.data()) < 0) {
    throw FormatError(file, field, with_hdf5_reason("read failed"));
  }
  return out;
}

std::vector<std::string> read_string_values(const Source& src, const Shape& s,
                                            const std::string& file, const std::string& field) {
  if (s.type_class != H5T_STRING) {
    throw FormatError(file, field, "expected strings, got " + s.text());
  }
  check_declared_size(src, s, file, field);
  Handle file_type = type_of(src);
  const size_t n = element_count(s);
  std::vector<std::string> out;
  out.reserve(n);
  if (n == 0) return out;
  if (H5Tis_variable_str(file_type.get()) > 0) {
    Handle mem_type(H5Tcopy(H5T_C_S1));
    H5Tset_size(mem_type.get(), H5T_VARIABLE);
    H5Tset_cset(mem_type.get(), H5Tget_cset(file_type.get()));
    std::vector<char*> ptrs(n, nullptr);
    if (read_raw(src, mem_type.get(), ptrs.data()) < 0) {
      throw FormatError(file, field, with_hdf5_reason("read failed"));
    }
    for (char* p : ptrs) out.emplace_back(p != nullptr ? p : "");
    Handle space = space_of(src);
    H5Dvlen_reclaim(mem_type.get(), space.get(), H5P_DEFAULT, ptrs.data());
    return out;
  }
  Handle mem_type(H5Tcopy(file_type.get()));
  const size_t size = H5Tget_size(mem_type.get());
  std::vector<char> raw(n * size);
  if (read_raw(src, mem_type.get(), raw.data()) < 0) {
    throw FormatError(file, field, with_hdf5_reason("read failed"));
  }
  const bool space_padded = H5Tget_strpad(file_type.get()) == H5T_STR_SPACEPAD;
  for (size_t i = 0; i < n; ++i) {
    const char* p = raw.data() + i * size;
    std::string v(p, strnlen(p, size));
    if (space_padded) v.erase(v.find_last_not_of(' ') + 1);
    out.push_back(std::move(v));
  }
  return out;
}

// Fixed-length UTF-8 strings padded with NULs (numpy's 'S' layout). Written instead of
// variable-length strings because those live in HDF5's global heap, where a corrupted file can
// crash or hang HDF5 1.10 inside H5Dread/H5Aread (seen when fuzzing); fixed-length strings are
// stored inline and read like any other array.
Handle fixed_string_type(size_t width) {
  Handle type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), width);
  H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  return type;
}

std::string expected_text(const std::vector<int64_t>& dims, const char* what) {
  std::string s = "[";
  for (size_t i = 0; i < dims.size(); ++i) {
    if (i > 0) s += ",";
    s += dims[i] < 0 ? "N" : std::to_string(dims[i]);
  }
  return s + "] " + what;
}

// Throws unless `s` has exactly the dims in `want` (-1 = any extent).
void require_dims(const Shape& s, const std::vector<int64_t>& want, const char* what,
                  const std::string& file, const std::string& field) {
  bool ok = s.dims.size() == want.size();
  for (size_t i = 0; ok && i < want.size(); ++i) {
    ok = want[i] < 0 || static_cast<int64_t>(s.dims[i]) == want[i];
  }
  if (!ok) {
    throw FormatError(file, field, "expected " + expected_text(want, what) + ", got " + s.text());
  }
}

void require_single(const Shape& s, const std::string& file, const std::string& field) {
  const bool ok = s.dims.empty() || (s.dims.size() == 1 && s.dims[0] == 1);
  if (!ok) throw FormatError(file, field, "expected a single value, got " + s.text());
}

}  // namespace

void silence_errors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

std::string take_error() {
  std::string message;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, keep_innermost, &message);
  H5Eclear2(H5E_DEFAULT);
  return message;
}

Handle& Handle::operator=(Handle&& other) noexcept {
  if (this != &other) {
    reset();
    id_ = other.id_;
    other.id_ = H5I_INVALID_HID;
  }
  return *this;
}

bool Handle::reset() {
  if (id_ < 0) return true;
  herr_t status = 0;
  switch (H5Iget_type(id_)) {
    case H5I_FILE:
      status = H5Fclose(id_);
      break;
    case H5I_GROUP:
      status = H5Gclose(id_);
      break;
    case H5I_DATASET:
      status = H5Dclose(id_);
      break;
    case H5I_ATTR:
      status = H5Aclose(id_);
      break;
    case H5I_DATASPACE:
      status = H5Sclose(id_);
      break;
    case H5I_DATATYPE:
      status = H5Tclose(id_);
      break;
    case H5I_GENPROP_LST:
      status = H5Pclose(id_);
      break;
    default:
      status = H5Idec_ref(id_);
      break;
  }
  id_ = H5I_INVALID_HID;
  return status >= 0;
}

std::string Shape::dims_text() const {
  if (dims.empty()) return "scalar";
  std::string s = "[";
  for (size_t i = 0; i < dims.size(); ++i) {
    if (i > 0) s += ",";
    s += std::to_string(dims[i]);
  }
  return s + "]";
}

std::string Shape::text() const {
  std::string type;
  switch (type_class) {
    case H5T_INTEGER:
      type = (is_signed ? "int" : "uint") + std::to_string(8 * type_size);
      break;
    case H5T_FLOAT:
      type = "float" + std::to_string(8 * type_size);
      break;
    case H5T_ENUM:
      type = "enum";
      break;
    case H5T_STRING:
      type = "string";
      break;
    case H5T_COMPOUND:
      type = "compound";
      break;
    default:
      type = "non-numeric";
      break;
  }
  return dims_text() + " " + type;
}

Group::Group(Handle handle, std::string file, std::string path)
    : handle_(std::move(handle)), file_(std::move(file)), path_(std::move(path)) {}

Group Group::open_file(const std::string& path) {
  silence_errors();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw IoError(path, "no such file");
  if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "not a regular file");
  const htri_t is_hdf5 = H5Fis_hdf5(path.c_str());
  if (is_hdf5 == 0) {
    take_error();
    throw IoError(path, "not an HDF5 file");
  }
  if (is_hdf5 < 0) throw IoError(path, with_hdf5_reason("cannot be read"));
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!file.valid()) {
    throw IoError(path, with_hdf5_reason("cannot be opened as HDF5 (truncated or corrupt?)"));
  }
  return Group(std::move(file), path, "");
}

// Creation properties without modification times, so the same scene gives byte-identical files.
static hid_t untimed_properties(hid_t cls) {
  const hid_t plist = H5Pcreate(cls);
  H5Pset_obj_track_times(plist, 0);
  return plist;
}

Group Group::create_file(const std::string& path) {
  silence_errors();
  // The 1.8+ object format stores small groups compactly: per-frame groups would otherwise cost
  // kilobytes each (files several times larger).
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS));
  H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_LATEST);
  Handle fcpl(untimed_properties(H5P_FILE_CREATE));  // the root group's header too
  Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()));
  if (!file.valid()) throw IoError(path, with_hdf5_reason("cannot be created"));
  return Group(std::move(file), path, "");
}

std::string Group::child_path(const std::string& name) const {
  return path_.empty() ? name : path_ + "/" + name;
}

bool Group::has(const std::string& name) const {
  const htri_t exists = H5Lexists(id(), name.c_str(), H5P_DEFAULT);
  if (exists < 0) take_error();
  return exists > 0;
}

bool Group::has_group(const std::string& name) const {
  if (!has(name)) return false;
  Handle object(H5Oopen(id(), name.c_str(), H5P_DEFAULT));
  if (!object.valid()) {
    take_error();
    return false;
  }
  return H5Iget_type(object.get()) == H5I_GROUP;
}

bool Group::has_dataset(const std::string& name) const {
  if (!has(name)) return false;
  Handle object(H5Oopen(id(), name.c_str(), H5P_DEFAULT));
  if (!object.valid()) {
    take_error();
    return false;
  }
  return H5Iget_type(object.get()) == H5I_DATASET;
}

// H5Literate callback: appends each link name to the vector in `names`.
static herr_t collect_link_name(hid_t, const char* name, const H5L_info_t*, void* names) {
  static_cast<std::vector<std::string>*>(names)->emplace_back(name);
  return 0;
}

std::vector<std::string> Group::children() const {
  // One pass in the order the links are stored, sorted here: asking for the i-th name by name
  // order (H5Lget_name_by_idx) rebuilds HDF5's sorted link table on every call, which makes
  // listing N frames cost N^2.
  std::vector<std::string> names;
  hsize_t next = 0;
  if (H5Literate(id(), H5_INDEX_NAME, H5_ITER_NATIVE, &next, collect_link_name, &names) < 0) {
    throw FormatError(file_, path_.empty() ? "/" : path_, with_hdf5_reason("cannot list group"));
  }
  std::sort(names.begin(), names.end());
  return names;
}

Group Group::group(const std::string& name) const {
  if (!has_group(name)) {
    throw FormatError(file_, child_path(name), has(name) ? "is not a group" : "missing group");
  }
  Handle g(H5Gopen2(id(), name.c_str(), H5P_DEFAULT));
  if (!g.valid()) throw FormatError(file_, child_path(name), with_hdf5_reason("cannot open"));
  return Group(std::move(g), file_, child_path(name));
}

Group Group::create_group(const std::string& name) const {
  Handle gcpl(untimed_properties(H5P_GROUP_CREATE));
  Handle g(H5Gcreate2(id(), name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT));
  if (!g.valid()) {
    throw IoError(file_, child_path(name) + ": " + with_hdf5_reason("cannot create group"));
  }
  return Group(std::move(g), file_, child_path(name));
}

void Group::close() {
  if (!handle_.reset()) throw IoError(file_, with_hdf5_reason("closing the file failed"));
}

Handle Group::open_dataset(const std::string& name) const {
  if (!has_dataset(name)) {
    throw FormatError(file_, child_path(name), has(name) ? "is not a dataset" : "missing dataset");
  }
  Handle ds(H5Dopen2(id(), name.c_str(), H5P_DEFAULT));
  if (!ds.valid()) throw FormatError(file_, child_path(name), with_hdf5_reason("cannot open"));
  return ds;
}

Handle Group::open_attribute(const std::string& name) const {
  Handle attr(H5Aopen(id(), name.c_str(), H5P_DEFAULT));
  if (!attr.valid()) {
    throw FormatError(file_, child_path("@" + name), with_hdf5_reason("cannot open attribute"));
  }
  return attr;
}

Shape Group::shape(const std::string& name) const {
  Handle ds = open_dataset(name);
  return shape_of({ds.get(), false});
}

MatrixXdR Group::read_matrix(const std::string& name, int64_t rows, int64_t cols) const {
  Handle ds = open_dataset(name);
  const Shape s = shape_of({ds.get(), false});
  const std::string field = child_path(name);
  if (!is_numeric(s)) {
    throw FormatError(file_, field,
                      "expected " + expected_text({rows, cols}, "numbers") + ", got " + s.text());
  }
  require_dims(s, {rows, cols}, "numbers", file_, field);
  const std::vector<double> values = read_doubles({ds.get(), false}, s, file_, field);
  return Eigen::Map<const MatrixXdR>(values.data(), static_cast<Eigen::Index>(s.dims[0]),
                                     static_cast<Eigen::Index>(s.dims[1]));
}

MatrixXlR Group::read_int_matrix(const std::string& name, int64_t rows, int64_t cols) const {
  Handle ds = open_dataset(name);
  const Shape s = shape_of({ds.get(), false});
  const std::string field = child_path(name);
  if (!is_integral(s)) {
    throw FormatError(file_, field,
                      "expected " + expected_text({rows, cols}, "integers") + ", got " + s.text());
  }
  require_dims(s, {rows, cols}, "integers", file_, field);
  const std::vector<int64_t> values = read_ints({ds.get(), false}, s, file_, field);
  return Eigen::Map<const MatrixXlR>(values.data(), static_cast<Eigen::Index>(s.dims[0]),
                                     static_cast<Eigen::Index>(s.dims[1]));
}

std::vector<double> Group::read_vector(const std::string& name, int64_t size) const {
  Handle ds = open_dataset(name);
  const Shape s = shape_of({ds.get(), false});
  const std::string field = child_path(name);
  if (!is_numeric(s)) {
    throw FormatError(file_, field,
                      "expected " + expected_text({size}, "numbers") + ", got " + s.text());
  }
  require_dims(s, {size}, "numbers", file_, field);
  return read_doubles({ds.get(), false}, s, file_, field);
}

std::vector<int64_t> Group::read_int_vector(const std::string& name, int64_t size) const {
  Handle ds = open_dataset(name);
  const Shape s = shape_of({ds.get(), false});
  const std::string field = child_path(name);
  if (!is_integral(s)) {
    throw FormatError(file_, field,
                      "expected " + expected_text({size}, "integers") + ", got " + s.text());
  }
  require_dims(s, {size}, "integers", file_, field);
  return read_ints({ds.get(), false}, s, file_, field);
}

std::vector<double> Group::read_array(const std::string& name, const std::vector<int64_t>& dims,
                                      Shape* shape_out) const {
  Handle ds = open_dataset(name);
  const Shape s = shape_of({ds.get(), false});
  const std::string field = child_path(name);
  if (!is_numeric(s)) {
    throw FormatError(file_, field,
                      "expected " + expected_text(dims, "numbers") + ", got " + s.text());
  }
  require_dims(s, dims, "numbers", file_, field);
  if (shape_out != nullptr) *shape_out = s;
  return read_doubles({ds.get(), false}, s, file_, field);
}

double Group::read_scalar(const std::string& name) const {
  Handle ds = open_dataset(name);
  const Shape s = shape_of({ds.get(), false});
  const std::string field = child_path(name);
  require_single(s, file_, field);
  return read_doubles({ds.get(), false}, s, file_, field).front();
}

int64_t Group::read_int_scalar(const std::string& name) const {
  Handle ds = open_dataset(name);
  const Shape s = shape_of({ds.get(), false});
  const std::string field = child_path(name);
  require_single(s, file_, field);
  return read_ints({ds.get(), false}, s, file_, field).front();
}

std::vector<std::string> Group::read_strings(const std::string& name, int64_t size) const {
  Handle ds = open_dataset(name);
  const Shape s = shape_of({ds.get(), false});
  const std::string field = child_path(name);
  if (s.type_class != H5T_STRING) {
    throw FormatError(file_, field,
                      "expected " + expected_text({size}, "strings") + ", got " + s.text());
  }
  require_dims(s, {size}, "strings", file_, field);
  return read_string_values({ds.get(), false}, s, file_, field);
}

bool Group::has_attribute(const std::string& name) const {
  const htri_t exists = H5Aexists(id(), name.c_str());
  if (exists < 0) take_error();
  return exists > 0;
}

std::optional<std::string> Group::string_attribute(const std::string& name) const {
  if (!has_attribute(name)) return std::nullopt;
  Handle attr = open_attribute(name);
  const Shape s = shape_of({attr.get(), true});
  const std::string field = child_path("@" + name);
  require_single(s, file_, field);
  return read_string_values({attr.get(), true}, s, file_, field).front();
}

std::optional<double> Group::double_attribute(const std::string& name) const {
  if (!has_attribute(name)) return std::nullopt;
  Handle attr = open_attribute(name);
  const Shape s = shape_of({attr.get(), true});
  const std::string field = child_path("@" + name);
  require_single(s, file_, field);
  return read_doubles({attr.get(), true}, s, file_, field).front();
}

std::optional<int64_t> Group::int_attribute(const std::string& name) const {
  if (!has_attribute(name)) return std::nullopt;
  Handle attr = open_attribute(name);
  const Shape s = shape_of({attr.get(), true});
  const std::string field = child_path("@" + name);
  require_single(s, file_, field);
  return read_ints({attr.get(), true}, s, file_, field).front();
}

std::optional<uint64_t> Group::uint_attribute(const std::string& name) const {
  if (!has_attribute(name)) return std::nullopt;
  Handle attr = open_attribute(name);
  const Shape s = shape_of({attr.get(), true});
  const std::string field = child_path("@" + name);
  require_single(s, file_, field);
  if (s.type_class == H5T_INTEGER && !s.is_signed) {
    uint64_t value = 0;
    if (H5Aread(attr.get(), H5T_NATIVE_UINT64, &value) < 0) {
      throw FormatError(file_, field, with_hdf5_reason("read failed"));
    }
    return value;
  }
  const int64_t value = read_ints({attr.get(), true}, s, file_, field).front();
  if (value < 0)
    throw FormatError(file_, field, "must not be negative, got " + std::to_string(value));
  return static_cast<uint64_t>(value);
}

void Group::write_array(const std::string& name, hid_t file_type, hid_t mem_type, const void* data,
                        const std::vector<hsize_t>& dims) const {
  const std::string field = child_path(name);
  Handle space(dims.empty()
                   ? H5Screate(H5S_SCALAR)
                   : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
  Handle dcpl(untimed_properties(H5P_DATASET_CREATE));
  Handle ds(H5Dcreate2(id(), name.c_str(), file_type, space.get(), H5P_DEFAULT, dcpl.get(),
                       H5P_DEFAULT));
  if (!space.valid() || !ds.valid()) {
    throw IoError(file_, field + ": " + with_hdf5_reason("cannot create dataset"));
  }
  size_t n = 1;
  for (hsize_t d : dims) n *= static_cast<size_t>(d);
  if (n > 0 && H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    throw IoError(file_, field + ": " + with_hdf5_reason("write failed"));
  }
}

void Group::write_matrix(const std::string& name, const double* data, hsize_t rows,
                         hsize_t cols) const {
  write_array(name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, data, {rows, cols});
}

void Group::write_int_matrix(const std::string& name, const int32_t* data, hsize_t rows,
                             hsize_t cols) const {
  write_array(name, H5T_STD_I32LE, H5T_NATIVE_INT32, data, {rows, cols});
}

void Group::write_vector(const std::string& name, const std::vector<double>& values) const {
  write_array(name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), {values.size()});
}

void Group::write_int_vector(const std::string& name, const std::vector<int32_t>& values) const {
  write_array(name, H5T_STD_I32LE, H5T_NATIVE_INT32, values.data(), {values.size()});
}

void Group::write_uint8_vector(const std::string& name, const std::vector<uint8_t>& values) const {
  write_array(name, H5T_STD_U8LE, H5T_NATIVE_UINT8, values.data(), {values.size()});
}

void Group::write_scalar(const std::string& name, double value) const {
  write_array(name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value, {});
}

void Group::write_int_scalar(const std::string& name, int32_t value) const {
  write_array(name, H5T_STD_I32LE, H5T_NATIVE_INT32, &value, {});
}

void Group::write_strings(const std::string& name, const std::vector<std::string>& values) const {
  size_t width = 1;
  for (const std::string& v : values) width = std::max(width, v.size());
  Handle type = fixed_string_type(width);
  std::vector<char> packed(width * values.size(), '\0');
  for (size_t i = 0; i < values.size(); ++i) {
    std::copy(values[i].begin(), values[i].end(), packed.begin() + static_cast<long>(i * width));
  }
  write_array(name, type.get(), type.get(), packed.data(), {values.size()});
}

void Group::write_scalar_attribute(const std::string& name, hid_t file_type, hid_t mem_type,
                                   const void* value) const {
  Handle space(H5Screate(H5S_SCALAR));
  Handle attr(H5Acreate2(id(), name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!attr.valid() || H5Awrite(attr.get(), mem_type, value) < 0) {
    throw IoError(file_,
                  child_path("@" + name) + ": " + with_hdf5_reason("cannot write attribute"));
  }
}

void Group::write_attribute(const std::string& name, const std::string& value) const {
  Handle type = fixed_string_type(std::max<size_t>(1, value.size()));
  std::vector<char> packed(std::max<size_t>(1, value.size()), '\0');
  std::copy(value.begin(), value.end(), packed.begin());
  write_scalar_attribute(name, type.get(), type.get(), packed.data());
}

void Group::write_attribute(const std::string& name, double value) const {
  write_scalar_attribute(name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
}

void Group::write_attribute(const std::string& name, int64_t value) const {
  write_scalar_attribute(name, H5T_STD_I64LE, H5T_NATIVE_INT64, &value);
}

void Group::write_attribute(const std::string& name, uint64_t value) const {
  write_scalar_attribute(name, H5T_STD_U64LE, H5T_NATIVE_UINT64, &value);
}

}  // namespace dynscope::h5
