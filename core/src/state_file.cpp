// Checkpoint containers (state_file.hpp): named arrays in one HDF5 file, written atomically and read
// back in an isolated child with a checksum over every array.
#include "tactus/core/state_file.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <cmath>

#include <cstdio>

#include "hdf5_handle.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/isolated.hpp"
#include "tactus/core/staged_output.hpp"

namespace fs = std::filesystem;

namespace tactus {

namespace {

constexpr const char* kFormat = "tactus state file 1";

// FNV-1a, 64 bit, over each array's name and bytes in name order: a corrupt byte anywhere (or an
// array renamed, cut or missing) changes it.
class Checksum {
 public:
  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h_ = (h_ ^ p[i]) * 0x100000001b3ULL;
  }
  void add_array(const std::string& name, const void* data, std::size_t n) {
    add(name.data(), name.size());
    const std::uint64_t size = n;
    add(&size, sizeof size);
    add(data, n);
  }
  std::string hex() const {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h_));
    return buf;
  }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
};

std::string checksum_of(const StateArrays& s) {
  Checksum c;
  for (const auto& [name, v] : s.reals) c.add_array("r:" + name, v.data(), v.size() * sizeof(double));
  for (const auto& [name, v] : s.integers) c.add_array("i:" + name, v.data(), v.size() * sizeof(std::int64_t));
  for (const auto& [name, v] : s.records) c.add_array("b:" + name, v.data(), v.size());
  c.add(s.kind.data(), s.kind.size());
  return c.hex();
}

void write_array(hid_t file, const std::string& name, hid_t file_type, hid_t memory_type, const void* data, std::size_t n, const fs::path& path) {
  const hsize_t dims[1] = {static_cast<hsize_t>(n)};
  H5Handle space(H5Screate_simple(1, dims, nullptr), H5Sclose);
  H5Handle ds(H5Dcreate2(file, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
  if (!ds.valid() || (n > 0 && H5Dwrite(ds.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0))
    throw_library_write_failure(path, "HDF5 failed writing " + name);
}

struct ReadContext {
  StateArrays* out;
  std::string file;
  std::uintmax_t file_size;
  std::string error;
};

// One dataset of the root group, by its stored type: 64-bit floats, 64-bit integers or bytes.
herr_t read_one(hid_t root, const char* name, const H5L_info_t*, void* data) {
  auto& ctx = *static_cast<ReadContext*>(data);
  try {
    H5Handle ds(H5Dopen2(root, name, H5P_DEFAULT), H5Dclose);
    if (!ds.valid()) throw InputError(ctx.file, name, "a readable dataset");
    H5Handle space(H5Dget_space(ds.get()), H5Sclose);
    if (H5Sget_simple_extent_ndims(space.get()) != 1) throw InputError(ctx.file, name, "a 1-D array");
    hsize_t n = 0;
    H5Sget_simple_extent_dims(space.get(), &n, nullptr);
    H5Handle type(H5Dget_type(ds.get()), H5Tclose);
    const H5T_class_t cls = H5Tget_class(type.get());
    const std::size_t bytes = H5Tget_size(type.get());
    // An array cannot hold more than its file: a corrupt header cannot make us allocate terabytes.
    if (static_cast<double>(n) * static_cast<double>(bytes) > static_cast<double>(ctx.file_size))
      throw InputError(ctx.file, name, "an array the file holds",
                       std::to_string(n) + " values of " + std::to_string(bytes) + " bytes (truncated or corrupt)");
    auto read = [&](hid_t memory_type, void* dst) {
      if (n > 0 && H5Dread(ds.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, dst) < 0)
        throw InputError(ctx.file, name, "readable values", "unreadable (truncated or corrupt)");
    };
    if (cls == H5T_FLOAT && bytes == 8) {
      std::vector<double>& v = ctx.out->reals[name];
      v.resize(n);
      read(H5T_NATIVE_DOUBLE, v.data());
    } else if (cls == H5T_INTEGER && bytes == 8) {
      std::vector<std::int64_t>& v = ctx.out->integers[name];
      v.resize(n);
      read(H5T_NATIVE_INT64, v.data());
    } else if (cls == H5T_INTEGER && bytes == 1) {
      std::string& v = ctx.out->records[name];
      v.resize(n);
      read(H5T_NATIVE_UINT8, v.data());
    } else {
      throw InputError(ctx.file, name, "64-bit floats, 64-bit integers or bytes");
    }
    return 0;
  } catch (const Error& e) {
    ctx.error = e.what();
    return -1;
  }
}

}  // namespace

void write_state_file(const fs::path& file, const StateArrays& state, const std::function<void(const char*)>& phase) {
  QuietHdf5 quiet;
  StagedOutput out(file);
  {
    H5Handle f(H5Fcreate(out.path().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!f.valid()) throw_library_write_failure(file, "HDF5 cannot create the file");
    for (const auto& [name, v] : state.reals) write_array(f.get(), name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.data(), v.size(), file);
    for (const auto& [name, v] : state.integers) write_array(f.get(), name, H5T_STD_I64LE, H5T_NATIVE_INT64, v.data(), v.size(), file);
    for (const auto& [name, v] : state.records) write_array(f.get(), name, H5T_STD_U8LE, H5T_NATIVE_UINT8, v.data(), v.size(), file);
    write_string_attribute(f.get(), "format", kFormat);
    write_string_attribute(f.get(), "kind", state.kind);
    if (phase) phase("data");
    // The checksum last: a file cut anywhere before it has none and is refused.
    write_string_attribute(f.get(), "checksum", checksum_of(state));
    if (H5Fflush(f.get(), H5F_SCOPE_GLOBAL) < 0 || !f.close()) throw_library_write_failure(file, "HDF5 failed finishing the file");
  }
  sync_file(out.path());
  if (phase) phase("written");
  out.commit();  // flushed to the disk, renamed, and the rename flushed too
  if (phase) phase("renamed");
}

StateArrays read_state_file(const fs::path& file, const std::string& kind) {
  const std::string fname = file.string();
  std::error_code ec;
  require_regular_file(file, "a " + kind + " file");
  const std::uintmax_t size = fs::file_size(file, ec);
  // libhdf5 is not hardened against hostile bytes: it reads in an isolated child process.
  const std::string bytes = run_isolated(
      fname, kind + " (HDF5)",
      [&](ByteWriter& w) {
        QuietHdf5 quiet;
        if (H5Fis_hdf5(file.c_str()) <= 0) throw InputError(fname, "", "an HDF5 file", "not HDF5, truncated or corrupt");
        H5Handle f(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
        if (!f.valid()) throw InputError(fname, "", "a readable HDF5 file", "cannot open (truncated?)");
        if (read_string_attribute(f.get(), "format", fname, "/") != kFormat)
          throw InputError(fname, "/@format", std::string("\"") + kFormat + "\"", "another format or none");
        StateArrays s;
        s.kind = read_string_attribute(f.get(), "kind", fname, "/");
        if (s.kind != kind) throw InputError(fname, "/@kind", "\"" + kind + "\"", "\"" + s.kind + "\"");
        const std::string stored = read_string_attribute(f.get(), "checksum", fname, "/");
        if (stored.empty()) throw InputError(fname, "/@checksum", "a checksum (written last)", "none: the file was not finished");
        ReadContext ctx{&s, fname, size, {}};
        if (H5Literate(f.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr, read_one, &ctx) < 0)
          throw InputError(fname, "", "readable arrays", ctx.error.empty() ? "unreadable (corrupt)" : ctx.error);
        if (checksum_of(s) != stored) throw InputError(fname, "/@checksum", stored, checksum_of(s) + " over the arrays read (corrupt)");
        w.put_string(s.kind);
        w.put<std::uint64_t>(s.reals.size());
        for (const auto& [name, v] : s.reals) w.put_string(name), w.put_vector(v);
        w.put<std::uint64_t>(s.integers.size());
        for (const auto& [name, v] : s.integers) w.put_string(name), w.put_vector(v);
        w.put<std::uint64_t>(s.records.size());
        for (const auto& [name, v] : s.records) w.put_string(name), w.put_string(v);
      },
      limits_for_file(fname, 20, 1));
  ByteReader r(bytes);
  StateArrays s;
  s.kind = r.get_string();
  for (auto n = r.get<std::uint64_t>(); n > 0; --n) {
    std::string name = r.get_string();
    s.reals[name] = r.get_vector<double>();
  }
  for (auto n = r.get<std::uint64_t>(); n > 0; --n) {
    std::string name = r.get_string();
    s.integers[name] = r.get_vector<std::int64_t>();
  }
  for (auto n = r.get<std::uint64_t>(); n > 0; --n) {
    std::string name = r.get_string();
    s.records[name] = r.get_string();
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
void StateArchive::size_error(const std::string& name, std::size_t expected, std::size_t found) const {
  throw InputError(file_, name, std::to_string(expected) + " values (this model's)", std::to_string(found) + ": a checkpoint of another model?");
}

void StateArchive::invalid(const std::string& name, const std::string& expected, const std::string& found) const {
  throw InputError(file_, name, expected, found + " (an edited or foreign checkpoint: start the run again without --restart)");
}

void StateArchive::require_finite(const std::string& name, const std::vector<double>& v) const {
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i])) invalid(name, "finite numbers", std::to_string(v[i]) + " at position " + std::to_string(i));
}

void StateArchive::missing(const std::string& name) const {
  throw InputError(file_, name, "an array named " + name + " (written by this version of tactus)", "none");
}

// An array of the archive as the file stores it (Stored: double or int64), in either direction.
template <class Stored, class T>
void StateArchive::io_array(std::map<std::string, std::vector<Stored>>& map, const std::string& name, std::vector<T>& v, std::size_t size) {
  if (!loading_) {
    auto& stored = map[name];
    stored.resize(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) stored[i] = static_cast<Stored>(v[i]);
    return;
  }
  const auto it = map.find(name);
  if (it == map.end()) missing(name);
  if (size != kAnySize && it->second.size() != size) size_error(name, size, it->second.size());
  v.resize(it->second.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<T>(it->second[i]);
}

void StateArchive::io(const std::string& name, std::vector<double>& v, std::size_t size) { io_array(arrays_.reals, name, v, size); }
void StateArchive::io(const std::string& name, std::vector<std::int32_t>& v, std::size_t size) { io_array(arrays_.integers, name, v, size); }
void StateArchive::io(const std::string& name, std::vector<std::int64_t>& v, std::size_t size) { io_array(arrays_.integers, name, v, size); }
void StateArchive::io(const std::string& name, std::vector<std::size_t>& v, std::size_t size) { io_array(arrays_.integers, name, v, size); }
void StateArchive::io(const std::string& name, double& x) {
  std::vector<double> v{x};
  io(name, v, 1);
  x = v[0];
}
void StateArchive::io(const std::string& name, std::string& text) {
  if (!loading_) {
    arrays_.records[name] = text;
    return;
  }
  const auto it = arrays_.records.find(name);
  if (it == arrays_.records.end()) missing(name);
  text = it->second;
}

}  // namespace tactus
