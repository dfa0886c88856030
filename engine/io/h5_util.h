// Internal HDF5 helpers of engine/io: RAII handles and shape/type-checked reads and writes.
// Not a public header: it includes <hdf5.h>, so only engine/io sources and tests/io use it.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/types.h"

namespace dynscope::h5 {

/// Row-major `[N,C]` doubles read from a dataset.
using MatrixXdR = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
/// Row-major `[N,C]` 64-bit integers read from a dataset.
using MatrixXlR = Eigen::Matrix<int64_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Turns off HDF5's automatic printing of its error stack for the calling thread (the stack is
/// per thread in the thread-safe library); every public io entry point calls it first.
void silence_errors();

/// Innermost message on the calling thread's HDF5 error stack ("" if none), then clears it.
std::string take_error();

/// Owns one HDF5 identifier (file, group, dataset, attribute, dataspace, datatype, property
/// list) and closes it with the matching H5*close. Move-only.
class Handle {
 public:
  Handle() = default;
  explicit Handle(hid_t id) : id_(id) {}
  ~Handle() { reset(); }
  Handle(Handle&& other) noexcept : id_(other.id_) { other.id_ = H5I_INVALID_HID; }
  Handle& operator=(Handle&& other) noexcept;
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  /// Closes the identifier now; returns false if HDF5 reported an error while closing.
  bool reset();

 private:
  hid_t id_ = H5I_INVALID_HID;
};

/// Shape and element class of a dataset or attribute.
struct Shape {
  std::vector<hsize_t> dims;  ///< Empty for a scalar.
  H5T_class_t type_class = H5T_NO_CLASS;
  size_t type_size = 0;  ///< Bytes per element in the file.
  bool is_signed = true;

  /// "[5,2]", or "scalar".
  std::string dims_text() const;
  /// "[5,2] float32", "scalar int64", "[3] string", ...
  std::string text() const;
};

/// An open group (or file root) together with the file path and its path inside the file,
/// so that every error can name both.
class Group {
 public:
  Group(Handle handle, std::string file, std::string path);

  /// Opens `path` read-only; throws IoError naming it if it is missing or not readable HDF5.
  static Group open_file(const std::string& path);
  /// Creates (truncates) `path`; throws IoError naming it on failure.
  static Group create_file(const std::string& path);

  hid_t id() const { return handle_.get(); }
  const std::string& file() const { return file_; }
  /// Path inside the file without a leading slash ("" for the root).
  const std::string& path() const { return path_; }
  /// "path/name" (or "name" at the root), the field name used in error messages.
  std::string child_path(const std::string& name) const;

  /// True if a link `name` exists here.
  bool has(const std::string& name) const;
  /// True if `name` exists here and is a group.
  bool has_group(const std::string& name) const;
  /// True if `name` exists here and is a dataset.
  bool has_dataset(const std::string& name) const;
  /// Names of the links in this group, in HDF5's (alphabetical) order.
  std::vector<std::string> children() const;

  /// Opens subgroup `name`; throws FormatError(file, child path) if it is missing.
  Group group(const std::string& name) const;
  /// Creates subgroup `name`; throws IoError on failure.
  Group create_group(const std::string& name) const;

  /// Closes the file (flushing it) if this is the root opened by create_file/open_file; throws
  /// IoError if HDF5 fails to close, e.g. because the disk is full.
  void close();

  // Reads. Numeric reads accept integer, float and enum (h5py bool) datasets and convert;
  // a wrong rank/shape/class or a failed read throws FormatError(file, "group/name", ...).

  /// Shape of dataset `name`; throws FormatError if it is missing or not a dataset.
  Shape shape(const std::string& name) const;
  /// Dataset `name` of shape `[N,cols]` (any N, or exactly `rows` if rows >= 0) as doubles.
  MatrixXdR read_matrix(const std::string& name, int64_t rows, int64_t cols) const;
  /// Integer dataset `name` of shape `[N,cols]` (exactly `rows` if rows >= 0).
  MatrixXlR read_int_matrix(const std::string& name, int64_t rows, int64_t cols) const;
  /// Dataset `name` of shape `[N]` (exactly `size` if size >= 0) as doubles.
  std::vector<double> read_vector(const std::string& name, int64_t size) const;
  /// Integer dataset `name` of shape `[N]` (exactly `size` if size >= 0).
  std::vector<int64_t> read_int_vector(const std::string& name, int64_t size) const;
  /// Numeric dataset `name` of any rank with the extents `dims` (-1: any), row-major, as doubles;
  /// `shape_out` (if given) receives its shape.
  std::vector<double> read_array(const std::string& name, const std::vector<int64_t>& dims,
                                 Shape* shape_out = nullptr) const;
  /// Numeric dataset `name` holding one value (scalar, or shape `[1]`).
  double read_scalar(const std::string& name) const;
  /// Integer dataset `name` holding one value (scalar, or shape `[1]`).
  int64_t read_int_scalar(const std::string& name) const;
  /// String dataset `name` of shape `[N]` (fixed or variable length; exactly `size` if >= 0).
  std::vector<std::string> read_strings(const std::string& name, int64_t size) const;

  /// True if this object carries attribute `name`.
  bool has_attribute(const std::string& name) const;
  /// String attribute, or nullopt if absent; throws FormatError if it is not a string.
  std::optional<std::string> string_attribute(const std::string& name) const;
  /// Numeric scalar attribute, or nullopt if absent; throws FormatError if not numeric.
  std::optional<double> double_attribute(const std::string& name) const;
  /// Integer scalar attribute, or nullopt if absent; throws FormatError if not an integer.
  std::optional<int64_t> int_attribute(const std::string& name) const;
  /// Unsigned integer scalar attribute (negative values rejected), or nullopt if absent.
  std::optional<uint64_t> uint_attribute(const std::string& name) const;

  // Writes (little-endian IEEE/standard types); a failure throws IoError(file, "group/name: ...").

  /// Writes `[rows,cols]` row-major doubles as float64.
  void write_matrix(const std::string& name, const double* data, hsize_t rows, hsize_t cols) const;
  /// Writes `[rows,cols]` row-major int32.
  void write_int_matrix(const std::string& name, const int32_t* data, hsize_t rows,
                        hsize_t cols) const;
  /// Writes `[N]` float64.
  void write_vector(const std::string& name, const std::vector<double>& values) const;
  /// Writes `[N]` int32.
  void write_int_vector(const std::string& name, const std::vector<int32_t>& values) const;
  /// Writes `[N]` uint8.
  void write_uint8_vector(const std::string& name, const std::vector<uint8_t>& values) const;
  /// Writes a scalar float64 dataset.
  void write_scalar(const std::string& name, double value) const;
  /// Writes a scalar int32 dataset.
  void write_int_scalar(const std::string& name, int32_t value) const;
  /// Writes `[N]` fixed-length UTF-8 strings, NUL-padded to the longest (h5py reads bytes).
  void write_strings(const std::string& name, const std::vector<std::string>& values) const;
  /// Writes a fixed-length UTF-8 string attribute.
  void write_attribute(const std::string& name, const std::string& value) const;
  /// Writes a float64 scalar attribute.
  void write_attribute(const std::string& name, double value) const;
  /// Writes an int64 scalar attribute.
  void write_attribute(const std::string& name, int64_t value) const;
  /// Writes a uint64 scalar attribute.
  void write_attribute(const std::string& name, uint64_t value) const;

 private:
  Handle open_dataset(const std::string& name) const;
  Handle open_attribute(const std::string& name) const;
  void write_array(const std::string& name, hid_t file_type, hid_t mem_type, const void* data,
                   const std::vector<hsize_t>& dims) const;
  void write_scalar_attribute(const std::string& name, hid_t file_type, hid_t mem_type,
                              const void* value) const;

  Handle handle_;
  std::string file_;
  std::string path_;
};

}  // namespace dynscope::h5
