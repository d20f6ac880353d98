// HDF5 and VTK image I/O for Volume<T>. All writes go through StagedOutput.
#include <hdf5.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLImageDataWriter.h>

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hdf5_handle.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/isolated.hpp"
#include "tactus/core/staged_output.hpp"
#include "tactus/core/volume.hpp"
#include "vtk_array_type.hpp"

namespace fs = std::filesystem;

namespace tactus {

void validate_direction(const Direction& d, const std::string& file, const std::string& field) {
  for (double x : d)
    if (!std::isfinite(x)) throw InputError(file, field, "a finite orientation matrix", "a non-finite entry");
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const double dot = d[a] * d[b] + d[3 + a] * d[3 + b] + d[6 + a] * d[6 + b];
      if (std::abs(dot - (a == b ? 1.0 : 0.0)) > 1e-4)
        throw InputError(file, field, "orthonormal axis directions (a rotation, possibly with a reflection)",
                         "axes " + std::to_string(a) + " and " + std::to_string(b) + " with dot product " + std::to_string(dot));
    }
}

void validate_volume_geometry(const std::array<int, 3>& dims, const std::array<double, 3>& spacing, const std::array<double, 3>& origin,
                              std::size_t bytes_per_voxel, const std::string& file, const std::string& field) {
  const char* axis = "xyz";
  double voxels = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1 || dims[a] > kMaxVolumeDim)
      throw InputError(file, field, "1 to " + std::to_string(kMaxVolumeDim) + " voxels along each axis",
                       std::to_string(dims[a]) + " along " + axis[a]);
    voxels *= dims[a];
    std::ostringstream v;
    v << spacing[a] << " m along " << axis[a];
    if (!std::isfinite(spacing[a]) || spacing[a] < kMinSpacing || spacing[a] > kMaxSpacing)
      throw InputError(file, field + " spacing", "a voxel size from 0.1 um to 1 m (stored in metres)", v.str());
    if (!std::isfinite(origin[a]) || std::abs(origin[a]) > kMaxOrigin) {
      std::ostringstream o;
      o << origin[a] << " m along " << axis[a];
      throw InputError(file, field + " origin", "a finite origin within 1 km (stored in metres)", o.str());
    }
  }
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  const double memory = pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 1e12;
  if (voxels * static_cast<double>(bytes_per_voxel) > 0.5 * memory) {
    std::ostringstream f;
    f << dims[0] << " x " << dims[1] << " x " << dims[2] << " voxels (" << voxels * static_cast<double>(bytes_per_voxel) / 1e9
      << " GB; this machine has " << memory / 1e9 << " GB)";
    throw InputError(file, field, "a volume that fits in half of this machine's memory", f.str());
  }
}

LabelTable parse_label_table(const std::string& text, const std::string& file, const std::string& field) {
  const auto table = nlohmann::json::parse(text, nullptr, false);
  if (table.is_discarded() || !table.is_object()) throw InputError(file, field, "a JSON object {\"id\": \"name\"}");
  LabelTable out;
  for (const auto& [key, value] : table.items()) {
    int id = -1;
    const auto [end, ec] = std::from_chars(key.data(), key.data() + key.size(), id);
    if (ec != std::errc() || end != key.data() + key.size() || id < 0 || id > 65535)
      throw InputError(file, field, "label ids from 0 to 65535", "\"" + key + "\"");
    if (!value.is_string() || value.get<std::string>().empty() || value.get<std::string>().size() > 200)
      throw InputError(file, field, "a name (a string of 1 to 200 characters) for label " + key, value.dump());
    out[id] = value.get<std::string>();
  }
  return out;
}

void write_string_attribute(hid_t obj, const char* name, const std::string& value) {
  H5Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), value.empty() ? 1 : value.size());
  H5Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  H5Handle attr(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  H5Awrite(attr.get(), type.get(), value.c_str());
}

// A string attribute of any kind HDF5 stores (fixed-length with NUL-terminated, NUL-padded or
// space-padded bytes, or variable-length, as h5py writes by default), read without conversion.
// "" when absent; InputError when it is not a single string.
std::string read_string_attribute(hid_t obj, const char* name, const std::string& file, const std::string& where) {
  if (H5Aexists(obj, name) <= 0) return {};
  H5Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  H5Handle ftype(H5Aget_type(attr.get()), H5Tclose);
  H5Handle space(H5Aget_space(attr.get()), H5Sclose);
  const std::string key = where + "@" + name;
  if (H5Tget_class(ftype.get()) != H5T_STRING) throw InputError(file, key, "a string attribute", "another type");
  if (H5Sget_simple_extent_npoints(space.get()) != 1) throw InputError(file, key, "a single string", "an array of strings");
  if (H5Tis_variable_str(ftype.get()) > 0) {
    H5Handle mtype(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mtype.get(), H5T_VARIABLE);
    H5Tset_cset(mtype.get(), H5Tget_cset(ftype.get()));
    char* text = nullptr;
    if (H5Aread(attr.get(), mtype.get(), &text) < 0) throw InputError(file, key, "a readable string");
    std::string s = text ? text : "";
    H5free_memory(text);
    return s;
  }
  const std::size_t n = H5Tget_size(ftype.get());
  if (n == 0 || n > (std::size_t{1} << 24)) throw InputError(file, key, "a string of at most 16 MB", std::to_string(n) + " bytes");
  std::string s(n, '\0');
  H5Handle mtype(H5Tcopy(ftype.get()), H5Tclose);  // the file's own layout: no conversion, nothing cut
  if (H5Aread(attr.get(), mtype.get(), s.data()) < 0) throw InputError(file, key, "a readable string");
  if (H5Tget_strpad(ftype.get()) == H5T_STR_SPACEPAD) {
    while (!s.empty() && s.back() == ' ') s.pop_back();
  } else {
    s.resize(std::strlen(s.c_str()));  // NUL-terminated or NUL-padded
  }
  return s;
}

namespace {

template <class T>
hid_t native_type();
template <>
hid_t native_type<std::uint8_t>() {
  return H5T_NATIVE_UINT8;
}
template <>
hid_t native_type<std::uint16_t>() {
  return H5T_NATIVE_UINT16;
}
template <>
hid_t native_type<std::int16_t>() {
  return H5T_NATIVE_INT16;
}
template <>
hid_t native_type<float>() {
  return H5T_NATIVE_FLOAT;
}

void write_doubles_attribute(hid_t obj, const char* name, const double* v, hsize_t n) {
  H5Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  H5Handle attr(H5Acreate2(obj, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, v);
}

void write_double3_attribute(hid_t obj, const char* name, const std::array<double, 3>& v) { write_doubles_attribute(obj, name, v.data(), 3); }

// The optional direction attribute (9 numbers, row by row); identity when absent (older files).
Direction read_direction_attribute(hid_t obj, const std::string& file, const std::string& dataset) {
  if (H5Aexists(obj, "direction") <= 0) return kIdentityDirection;
  H5Handle attr(H5Aopen(obj, "direction", H5P_DEFAULT), H5Aclose);
  H5Handle space(H5Aget_space(attr.get()), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != 9) throw InputError(file, dataset + "@direction", "9 numbers (a 3x3 matrix, row by row)");
  Direction d{};
  if (H5Aread(attr.get(), H5T_NATIVE_DOUBLE, d.data()) < 0) throw InputError(file, dataset + "@direction", "numeric values");
  validate_direction(d, file, dataset + "@direction");
  return d;
}

std::array<double, 3> read_double3_attribute(hid_t obj, const char* name, const std::string& file, const std::string& dataset) {
  if (H5Aexists(obj, name) <= 0) throw InputError(file, dataset + "@" + name, "an attribute of 3 numbers (x, y, z)", "none");
  H5Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  H5Handle space(H5Aget_space(attr.get()), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != 3) throw InputError(file, dataset + "@" + name, "3 numbers (x, y, z)");
  std::array<double, 3> v{};
  if (H5Aread(attr.get(), H5T_NATIVE_DOUBLE, v.data()) < 0) throw InputError(file, dataset + "@" + name, "numeric values");
  return v;
}

// The voxels of a 3-D dataset as T, slice by slice through a wide integer or a double, so a value
// T cannot hold (a label -1 in an int8 file, 300 in an int64 one) is an error instead of being
// clamped silently by HDF5's conversion.
template <class T>
void read_voxels(hid_t ds, hid_t ftype, const hsize_t shape[3], Volume<T>& v, const std::string& file, const std::string& dataset) {
  const bool integer_file = H5Tget_class(ftype) == H5T_INTEGER;
  const hsize_t slice = shape[1] * shape[2];
  // Read in slabs of whole chunks along z: a chunked dataset (h5py chunks by default) read one z
  // slice at a time decompresses each chunk once per slice it spans (a 600^3 volume took over 20 s;
  // h5py reads it in 1.2). A contiguous one is read 16 slices at a time.
  hsize_t depth = 16;
  {
    H5Handle plist(H5Dget_create_plist(ds), H5Pclose);
    hsize_t chunk[3] = {1, 1, 1};
    if (plist.valid() && H5Pget_layout(plist.get()) == H5D_CHUNKED && H5Pget_chunk(plist.get(), 3, chunk) == 3) depth = chunk[0];
  }
  depth = std::clamp<hsize_t>(depth, 1, std::max<hsize_t>(1, (hsize_t{256} << 20) / (8 * slice)));  // at most 256 MB of buffer
  depth = std::min(depth, shape[0]);
  H5Handle fspace(H5Dget_space(ds), H5Sclose);
  std::vector<std::int64_t> ibuf(integer_file ? depth * slice : 0);
  std::vector<double> dbuf(integer_file ? 0 : depth * slice);
  const double lo = static_cast<double>(std::numeric_limits<T>::lowest()), hi = static_cast<double>(std::numeric_limits<T>::max());
  for (hsize_t z0 = 0; z0 < shape[0]; z0 += depth) {
    const hsize_t n = std::min(depth, shape[0] - z0);
    const hsize_t offset[3] = {z0, 0, 0}, count[3] = {n, shape[1], shape[2]};
    H5Handle mspace(H5Screate_simple(3, count, nullptr), H5Sclose);
    H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, offset, nullptr, count, nullptr);
    const herr_t ok = integer_file ? H5Dread(ds, H5T_NATIVE_INT64, mspace.get(), fspace.get(), H5P_DEFAULT, ibuf.data())
                                   : H5Dread(ds, H5T_NATIVE_DOUBLE, mspace.get(), fspace.get(), H5P_DEFAULT, dbuf.data());
    if (ok < 0)
      throw InputError(file, dataset, "readable voxel data",
                       "slices z = " + std::to_string(z0) + " to " + std::to_string(z0 + n - 1) + " cannot be read (truncated or corrupt)");
    for (hsize_t z = z0; z < z0 + n; ++z) {
      const std::int64_t* ib = integer_file ? ibuf.data() + (z - z0) * slice : nullptr;
      const double* db = integer_file ? nullptr : dbuf.data() + (z - z0) * slice;
      T* out = v.data.data() + z * slice;
      for (hsize_t i = 0; i < slice; ++i) {
        const double value = integer_file ? static_cast<double>(ib[i]) : db[i];
        if (!(value >= lo && value <= hi)) {
          std::ostringstream f;
          f << value << " at voxel (x " << i % shape[2] << ", y " << i / shape[2] << ", z " << z << ")";
          throw InputError(file, dataset,
                           std::string("values a ") + (std::is_integral_v<T> ? "label" : "voxel") + " of this volume can hold, in [" +
                               std::to_string(static_cast<long long>(lo)) + ", " + std::to_string(static_cast<long long>(hi)) + "]",
                           f.str());
        }
        out[i] = static_cast<T>(value);
      }
    }
  }
}

}  // namespace

template <class T>
void write_h5(const fs::path& file, const std::string& dataset, const Volume<T>& volume, const LabelTable* labels) {
  if (volume.size() != static_cast<std::size_t>(volume.dims[0]) * volume.dims[1] * volume.dims[2])
    throw InputError(file.string(), dataset, "data size equal to nx*ny*nz");
  QuietHdf5 quiet;
  StagedOutput out(file);
  {
    H5Handle f(H5Fcreate(out.path().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!f.valid()) throw WriteError(file.string(), "HDF5 cannot create the file");
    const hsize_t shape[3] = {static_cast<hsize_t>(volume.dims[2]), static_cast<hsize_t>(volume.dims[1]), static_cast<hsize_t>(volume.dims[0])};
    H5Handle space(H5Screate_simple(3, shape, nullptr), H5Sclose);
    // Chunked + deflate: label volumes compress ~20x, CT a little; chunks of whole slices.
    H5Handle plist(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    if (volume.size() > 0) {
      const hsize_t chunk[3] = {1, shape[1], shape[2]};
      H5Pset_chunk(plist.get(), 3, chunk);
      H5Pset_deflate(plist.get(), 4);
    }
    H5Handle ds(H5Dcreate2(f.get(), dataset.c_str(), native_type<T>(), space.get(), H5P_DEFAULT, plist.get(), H5P_DEFAULT), H5Dclose);
    if (!ds.valid()) throw InputError(file.string(), dataset, "a dataset that can be created");
    if (volume.size() > 0 && H5Dwrite(ds.get(), native_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, volume.data.data()) < 0)
      throw_library_write_failure(file, "HDF5 failed writing " + dataset);
    write_double3_attribute(ds.get(), "spacing", volume.spacing);
    write_double3_attribute(ds.get(), "origin", volume.origin);
    write_doubles_attribute(ds.get(), "direction", volume.direction.data(), 9);
    write_string_attribute(ds.get(), "units", "m");
    write_string_attribute(ds.get(), "axes", "z,y,x (attributes are x,y,z)");
    if (labels) {
      nlohmann::json table = nlohmann::json::object();
      for (const auto& [id, name] : *labels) table[std::to_string(id)] = name;
      write_string_attribute(ds.get(), "label_table", table.dump());
    }
    if (!ds.close() || H5Fflush(f.get(), H5F_SCOPE_GLOBAL) < 0 || !f.close()) throw_library_write_failure(file, "HDF5 failed finishing the file");
  }
  out.commit();
}

namespace {

// The direct read, run in an isolated child process (see read_h5).
template <class T>
Volume<T> read_h5_direct(const fs::path& file, const std::string& dataset, LabelTable* labels) {
  const std::string fname = file.string();
  QuietHdf5 quiet;
  if (H5Fis_hdf5(file.c_str()) <= 0) throw InputError(fname, "", "an HDF5 file", "not HDF5 or corrupt");
  H5Handle f(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!f.valid()) throw InputError(fname, "", "a readable HDF5 file", "cannot open (truncated?)");
  if (H5Lexists(f.get(), dataset.c_str(), H5P_DEFAULT) <= 0) throw InputError(fname, dataset, "a dataset named " + dataset, "none");
  H5Handle ds(H5Dopen2(f.get(), dataset.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) throw InputError(fname, dataset, "a readable dataset");
  H5Handle space(H5Dget_space(ds.get()), H5Sclose);
  if (H5Sget_simple_extent_ndims(space.get()) != 3)
    throw InputError(fname, dataset, "a 3-D dataset (z, y, x)", std::to_string(H5Sget_simple_extent_ndims(space.get())) + " dimensions");
  hsize_t shape[3];
  H5Sget_simple_extent_dims(space.get(), shape, nullptr);
  H5Handle ftype(H5Dget_type(ds.get()), H5Tclose);
  const H5T_class_t cls = H5Tget_class(ftype.get());
  if (cls != H5T_INTEGER && cls != H5T_FLOAT) throw InputError(fname, dataset, "numeric voxels");
  if (std::is_integral_v<T> && cls != H5T_INTEGER) throw InputError(fname, dataset, "integer voxels", "floating-point voxels");

  Volume<T> v;
  for (int a = 0; a < 3; ++a)
    if (shape[a] == 0 || shape[a] > static_cast<hsize_t>(kMaxVolumeDim))
      throw InputError(fname, dataset, "1 to " + std::to_string(kMaxVolumeDim) + " voxels along each axis",
                       std::to_string(shape[2]) + " x " + std::to_string(shape[1]) + " x " + std::to_string(shape[0]));
  v.dims = {static_cast<int>(shape[2]), static_cast<int>(shape[1]), static_cast<int>(shape[0])};
  v.spacing = read_double3_attribute(ds.get(), "spacing", fname, dataset);
  v.origin = read_double3_attribute(ds.get(), "origin", fname, dataset);
  v.direction = read_direction_attribute(ds.get(), fname, dataset);
  validate_volume_geometry(v.dims, v.spacing, v.origin, sizeof(T), fname, dataset);
  // The declared shape must be backed by the file: stored bytes cannot be more than ~1000x
  // smaller than the raw data (deflate's limit), so a 6 kB file cannot declare 10^15 voxels.
  const double raw =
      static_cast<double>(shape[0]) * static_cast<double>(shape[1]) * static_cast<double>(shape[2]) * static_cast<double>(H5Tget_size(ftype.get()));
  const double stored = static_cast<double>(H5Dget_storage_size(ds.get()));
  std::error_code ec;
  const double file_size = static_cast<double>(fs::file_size(file, ec));
  if (raw > 2000.0 * std::max(stored, 1.0) + 1e6 || stored > file_size + 1e6)
    throw InputError(fname, dataset, "voxel data the file holds",
                     "a declared " + std::to_string(shape[2]) + " x " + std::to_string(shape[1]) + " x " + std::to_string(shape[0]) +
                         " volume with " + std::to_string(static_cast<long long>(stored)) + " bytes stored in a " +
                         std::to_string(static_cast<long long>(file_size)) + "-byte file (truncated or corrupt)");
  const std::string units = read_string_attribute(ds.get(), "units", fname, dataset);
  if (!units.empty() && units != "m") throw InputError(fname, dataset + "@units", "\"m\" (tactus stores SI lengths)", "\"" + units + "\"");
  v.data.resize(static_cast<std::size_t>(shape[0] * shape[1] * shape[2]));
  read_voxels(ds.get(), ftype.get(), shape, v, fname, dataset);
  if (labels) {
    labels->clear();
    const std::string text = read_string_attribute(ds.get(), "label_table", fname, dataset);
    if (!text.empty()) *labels = parse_label_table(text, fname, dataset + "@label_table");
  }
  return v;
}

// The volume an isolated reader sent back: dims, spacing, origin, then the voxels.
template <class T>
Volume<T> get_volume(ByteReader& r) {
  Volume<T> v;
  v.dims = r.get<std::array<int, 3>>();
  v.spacing = r.get<std::array<double, 3>>();
  v.origin = r.get<std::array<double, 3>>();
  v.direction = r.get<Direction>();
  v.data = r.get_vector<T>();
  return v;
}

}  // namespace

template <class T>
Volume<T> read_h5(const fs::path& file, const std::string& dataset, LabelTable* labels) {
  const std::string fname = file.string();
  std::error_code ec;
  require_regular_file(file, "an HDF5 file");
  // libhdf5 is not hardened against hostile bytes: it reads in an isolated child process.
  const std::string bytes = run_isolated(
      fname, "HDF5 file",
      [&](ByteWriter& w) {
        LabelTable table;
        const Volume<T> v = read_h5_direct<T>(file, dataset, labels ? &table : nullptr);
        w.put(v.dims), w.put(v.spacing), w.put(v.origin), w.put(v.direction);
        w.put_vector(v.data);
        w.put<std::uint64_t>(table.size());
        for (const auto& [id, name] : table) w.put(id), w.put_string(name);
      },
      // A compressed file can hold far more voxels than its size says: 60 s base (a valid 600^3
      // labels.h5 reads in a few seconds) before a stuck read is called corrupt.
      limits_for_file(fname, 60, 2));
  ByteReader r(bytes);
  Volume<T> v = get_volume<T>(r);
  const auto n = r.get<std::uint64_t>();
  if (labels) labels->clear();
  for (std::uint64_t i = 0; i < n; ++i) {
    const int id = r.get<int>();
    std::string name = r.get_string();
    if (labels) (*labels)[id] = std::move(name);
  }
  return v;
}

template <class T>
void write_vti(const fs::path& file, const Volume<T>& volume, const std::string& array_name) {
  vtkNew<vtkImageData> image;
  image->SetDimensions(volume.dims[0], volume.dims[1], volume.dims[2]);
  image->SetSpacing(volume.spacing.data());
  image->SetOrigin(volume.origin.data());
  image->SetDirectionMatrix(volume.direction.data());  // ParaView places the voxels where they are in the world
  auto array = make_vtk_array<T>();
  array->SetName(array_name.c_str());
  array->SetNumberOfComponents(1);
  array->SetNumberOfTuples(static_cast<vtkIdType>(volume.size()));
  std::copy(volume.data.begin(), volume.data.end(), array->GetPointer(0));
  image->GetPointData()->SetScalars(array);
  StagedOutput out(file);
  vtkNew<vtkXMLImageDataWriter> writer;
  writer->SetFileName(out.path().c_str());
  writer->SetInputData(image);
  writer->SetDataModeToAppended();
  writer->SetCompressorTypeToZLib();
  if (writer->Write() != 1 || writer->GetErrorCode() != 0) throw_library_write_failure(file, "VTK failed writing the image");
  out.commit("</VTKFile>\n", "VTK image");
}

template <class T>
Volume<T> read_vti(const fs::path& file, const std::string& array_name) {
  const std::string fname = file.string();
  std::error_code ec;
  require_regular_file(file, "a VTK image (.vti)");
  // VTK's XML reader is not hardened against hostile bytes: it reads in an isolated child process.
  const std::string bytes = run_isolated(
      fname, "VTK image (.vti)",
      [&](ByteWriter& w) {
        vtkObject::GlobalWarningDisplayOff();  // (in the child: our message replaces VTK's)
        vtkNew<vtkXMLImageDataReader> reader;
        reader->SetFileName(file.c_str());
        reader->Update();
        vtkImageData* image = reader->GetOutput();
        if (reader->GetErrorCode() != 0 || !image || image->GetNumberOfPoints() == 0)
          throw InputError(fname, "", "a VTK XML image (.vti)", "unreadable or empty");
        vtkDataArray* array = image->GetPointData()->GetArray(array_name.c_str());
        if (!array) throw InputError(fname, array_name, "a point-data array named " + array_name);
        std::array<int, 3> d{};
        std::array<double, 3> spacing{}, origin{};
        Direction direction{};
        image->GetDimensions(d.data());
        image->GetSpacing(spacing.data());
        image->GetOrigin(origin.data());
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) direction[static_cast<std::size_t>(3 * r + c)] = image->GetDirectionMatrix()->GetElement(r, c);
        validate_volume_geometry(d, spacing, origin, sizeof(T), fname, array_name);
        validate_direction(direction, fname, array_name + " direction");
        if (array->GetNumberOfTuples() != image->GetNumberOfPoints() || array->GetNumberOfComponents() != 1)
          throw InputError(fname, array_name, "one value per voxel");
        std::vector<T> data(static_cast<std::size_t>(array->GetNumberOfTuples()));
        const double lo = static_cast<double>(std::numeric_limits<T>::lowest()), hi = static_cast<double>(std::numeric_limits<T>::max());
        for (vtkIdType i = 0; i < array->GetNumberOfTuples(); ++i) {
          const double value = array->GetComponent(i, 0);
          if (!(value >= lo && value <= hi)) throw InputError(fname, array_name, "values this volume type can hold", std::to_string(value));
          data[static_cast<std::size_t>(i)] = static_cast<T>(value);
        }
        w.put(d), w.put(spacing), w.put(origin), w.put(direction);
        w.put_vector(data);
      },
      limits_for_file(fname, 20, 2));
  ByteReader r(bytes);
  return get_volume<T>(r);
}

#define TACTUS_VOLUME_IO(T)                                                                            \
  template void write_h5<T>(const fs::path&, const std::string&, const Volume<T>&, const LabelTable*); \
  template Volume<T> read_h5<T>(const fs::path&, const std::string&, LabelTable*);                     \
  template void write_vti<T>(const fs::path&, const Volume<T>&, const std::string&);                   \
  template Volume<T> read_vti<T>(const fs::path&, const std::string&);
TACTUS_VOLUME_IO(std::uint8_t)
TACTUS_VOLUME_IO(std::uint16_t)
TACTUS_VOLUME_IO(std::int16_t)
TACTUS_VOLUME_IO(float)
#undef TACTUS_VOLUME_IO

}  // namespace tactus
