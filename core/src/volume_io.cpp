// HDF5 and VTK image I/O for Volume<T>. All writes go through StagedOutput.
#include <hdf5.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLImageDataWriter.h>

#include <nlohmann/json.hpp>

#include "tactus/core/error.hpp"
#include "tactus/core/staged_output.hpp"
#include "tactus/core/volume.hpp"
#include "vtk_array_type.hpp"

namespace fs = std::filesystem;

namespace tactus {

namespace {

template <class T>
hid_t native_type();
template <>
hid_t native_type<std::uint8_t>() { return H5T_NATIVE_UINT8; }
template <>
hid_t native_type<std::uint16_t>() { return H5T_NATIVE_UINT16; }
template <>
hid_t native_type<std::int16_t>() { return H5T_NATIVE_INT16; }
template <>
hid_t native_type<float>() { return H5T_NATIVE_FLOAT; }

// RAII for HDF5 identifiers, so every error path closes what it opened.
class H5Handle {
 public:
  H5Handle(hid_t id, herr_t (*closer)(hid_t)) : id_(id), closer_(closer) {}
  ~H5Handle() {
    if (id_ >= 0) closer_(id_);
  }
  H5Handle(const H5Handle&) = delete;
  H5Handle& operator=(const H5Handle&) = delete;
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*closer_)(hid_t);
};

// Silences HDF5's own error stack printing: we report errors ourselves, once.
struct QuietHdf5 {
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func, data); }
  H5E_auto2_t func = nullptr;
  void* data = nullptr;
};

void write_double3_attribute(hid_t obj, const char* name, const std::array<double, 3>& v) {
  const hsize_t n = 3;
  H5Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  H5Handle attr(H5Acreate2(obj, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, v.data());
}

void write_string_attribute(hid_t obj, const char* name, const std::string& value) {
  H5Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), value.empty() ? 1 : value.size());
  H5Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  H5Handle attr(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  H5Awrite(attr.get(), type.get(), value.c_str());
}

std::array<double, 3> read_double3_attribute(hid_t obj, const char* name, const std::string& file,
                                             const std::string& dataset) {
  if (H5Aexists(obj, name) <= 0)
    throw InputError(file, dataset + "@" + name, "an attribute of 3 numbers (x, y, z)", "none");
  H5Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  H5Handle space(H5Aget_space(attr.get()), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != 3)
    throw InputError(file, dataset + "@" + name, "3 numbers (x, y, z)");
  std::array<double, 3> v{};
  if (H5Aread(attr.get(), H5T_NATIVE_DOUBLE, v.data()) < 0)
    throw InputError(file, dataset + "@" + name, "numeric values");
  return v;
}

std::string read_string_attribute(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) <= 0) return {};
  H5Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  H5Handle ftype(H5Aget_type(attr.get()), H5Tclose);
  if (H5Tget_class(ftype.get()) != H5T_STRING || H5Tis_variable_str(ftype.get()) > 0) return {};
  const std::size_t n = H5Tget_size(ftype.get());
  std::string s(n, '\0');
  H5Handle mtype(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(mtype.get(), n);
  H5Aread(attr.get(), mtype.get(), s.data());
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

}  // namespace

template <class T>
void write_h5(const fs::path& file, const std::string& dataset, const Volume<T>& volume,
              const LabelTable* labels) {
  if (volume.size() != static_cast<std::size_t>(volume.dims[0]) * volume.dims[1] * volume.dims[2])
    throw InputError(file.string(), dataset, "data size equal to nx*ny*nz");
  QuietHdf5 quiet;
  StagedOutput out(file);
  {
    H5Handle f(H5Fcreate(out.path().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!f.valid()) throw InputError(file.string(), "", "a writable HDF5 file");
    const hsize_t shape[3] = {static_cast<hsize_t>(volume.dims[2]), static_cast<hsize_t>(volume.dims[1]),
                              static_cast<hsize_t>(volume.dims[0])};
    H5Handle space(H5Screate_simple(3, shape, nullptr), H5Sclose);
    // Chunked + deflate: label volumes compress ~20x, CT a little; chunks of whole slices.
    H5Handle plist(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    if (volume.size() > 0) {
      const hsize_t chunk[3] = {1, shape[1], shape[2]};
      H5Pset_chunk(plist.get(), 3, chunk);
      H5Pset_deflate(plist.get(), 4);
    }
    H5Handle ds(H5Dcreate2(f.get(), dataset.c_str(), native_type<T>(), space.get(), H5P_DEFAULT,
                           plist.get(), H5P_DEFAULT),
                H5Dclose);
    if (!ds.valid()) throw InputError(file.string(), dataset, "a dataset that can be created");
    if (volume.size() > 0 &&
        H5Dwrite(ds.get(), native_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, volume.data.data()) < 0)
      throw InputError(file.string(), dataset, "a successful write");
    write_double3_attribute(ds.get(), "spacing", volume.spacing);
    write_double3_attribute(ds.get(), "origin", volume.origin);
    write_string_attribute(ds.get(), "units", "m");
    write_string_attribute(ds.get(), "axes", "z,y,x (attributes are x,y,z)");
    if (labels) {
      nlohmann::json table = nlohmann::json::object();
      for (const auto& [id, name] : *labels) table[std::to_string(id)] = name;
      write_string_attribute(ds.get(), "label_table", table.dump());
    }
  }
  out.commit();
}

template <class T>
Volume<T> read_h5(const fs::path& file, const std::string& dataset, LabelTable* labels) {
  const std::string fname = file.string();
  if (!fs::exists(file)) throw InputError(fname, "", "an existing HDF5 file", "no such file");
  QuietHdf5 quiet;
  if (H5Fis_hdf5(file.c_str()) <= 0) throw InputError(fname, "", "an HDF5 file", "not HDF5 or corrupt");
  H5Handle f(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!f.valid()) throw InputError(fname, "", "a readable HDF5 file", "cannot open (truncated?)");
  if (H5Lexists(f.get(), dataset.c_str(), H5P_DEFAULT) <= 0)
    throw InputError(fname, dataset, "a dataset named " + dataset, "none");
  H5Handle ds(H5Dopen2(f.get(), dataset.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) throw InputError(fname, dataset, "a readable dataset");
  H5Handle space(H5Dget_space(ds.get()), H5Sclose);
  if (H5Sget_simple_extent_ndims(space.get()) != 3)
    throw InputError(fname, dataset, "a 3-D dataset (z, y, x)",
                     std::to_string(H5Sget_simple_extent_ndims(space.get())) + " dimensions");
  hsize_t shape[3];
  H5Sget_simple_extent_dims(space.get(), shape, nullptr);
  H5Handle ftype(H5Dget_type(ds.get()), H5Tclose);
  const H5T_class_t cls = H5Tget_class(ftype.get());
  if (cls != H5T_INTEGER && cls != H5T_FLOAT) throw InputError(fname, dataset, "numeric voxels");
  if (std::is_integral_v<T> && cls != H5T_INTEGER)
    throw InputError(fname, dataset, "integer voxels", "floating-point voxels");

  Volume<T> v;
  v.dims = {static_cast<int>(shape[2]), static_cast<int>(shape[1]), static_cast<int>(shape[0])};
  v.spacing = read_double3_attribute(ds.get(), "spacing", fname, dataset);
  v.origin = read_double3_attribute(ds.get(), "origin", fname, dataset);
  for (int a = 0; a < 3; ++a)
    if (!(v.spacing[a] > 0))
      throw InputError(fname, dataset + "@spacing", "positive spacing in x, y, z",
                       std::to_string(v.spacing[a]) + " along axis " + std::to_string(a));
  const std::string units = read_string_attribute(ds.get(), "units");
  if (!units.empty() && units != "m")
    throw InputError(fname, dataset + "@units", "\"m\" (tactus stores SI lengths)", "\"" + units + "\"");
  v.data.resize(static_cast<std::size_t>(shape[0] * shape[1] * shape[2]));
  if (!v.data.empty() &&
      H5Dread(ds.get(), native_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data.data()) < 0)
    throw InputError(fname, dataset, "readable voxel data", "read failed (truncated or out of range)");
  if (labels) {
    labels->clear();
    const std::string text = read_string_attribute(ds.get(), "label_table");
    if (!text.empty()) {
      const auto table = nlohmann::json::parse(text, nullptr, false);
      if (table.is_discarded() || !table.is_object())
        throw InputError(fname, dataset + "@label_table", "a JSON object {\"id\": \"name\"}");
      for (const auto& [key, value] : table.items()) {
        if (!value.is_string()) throw InputError(fname, dataset + "@label_table", "string names");
        try {
          (*labels)[std::stoi(key)] = value.template get<std::string>();
        } catch (const std::exception&) {
          throw InputError(fname, dataset + "@label_table", "integer label ids", "\"" + key + "\"");
        }
      }
    }
  }
  return v;
}

template <class T>
void write_vti(const fs::path& file, const Volume<T>& volume, const std::string& array_name) {
  vtkNew<vtkImageData> image;
  image->SetDimensions(volume.dims[0], volume.dims[1], volume.dims[2]);
  image->SetSpacing(volume.spacing.data());
  image->SetOrigin(volume.origin.data());
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
  if (writer->Write() != 1) throw InputError(file.string(), "", "a writable .vti file");
  out.commit();
}

template <class T>
Volume<T> read_vti(const fs::path& file, const std::string& array_name) {
  if (!fs::exists(file)) throw InputError(file.string(), "", "an existing .vti file", "no such file");
  vtkNew<vtkXMLImageDataReader> reader;
  reader->SetFileName(file.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || !image || image->GetNumberOfPoints() == 0)
    throw InputError(file.string(), "", "a VTK XML image (.vti)", "unreadable or empty");
  vtkDataArray* array = image->GetPointData()->GetArray(array_name.c_str());
  if (!array) throw InputError(file.string(), array_name, "a point-data array named " + array_name);
  Volume<T> v;
  int d[3];
  image->GetDimensions(d);
  v.dims = {d[0], d[1], d[2]};
  image->GetSpacing(v.spacing.data());
  image->GetOrigin(v.origin.data());
  v.data.resize(static_cast<std::size_t>(array->GetNumberOfTuples()));
  for (vtkIdType i = 0; i < array->GetNumberOfTuples(); ++i)
    v.data[static_cast<std::size_t>(i)] = static_cast<T>(array->GetComponent(i, 0));
  return v;
}

#define TACTUS_VOLUME_IO(T)                                                                     \
  template void write_h5<T>(const fs::path&, const std::string&, const Volume<T>&,              \
                            const LabelTable*);                                                 \
  template Volume<T> read_h5<T>(const fs::path&, const std::string&, LabelTable*);              \
  template void write_vti<T>(const fs::path&, const Volume<T>&, const std::string&);            \
  template Volume<T> read_vti<T>(const fs::path&, const std::string&);
TACTUS_VOLUME_IO(std::uint8_t)
TACTUS_VOLUME_IO(std::uint16_t)
TACTUS_VOLUME_IO(std::int16_t)
TACTUS_VOLUME_IO(float)
#undef TACTUS_VOLUME_IO

}  // namespace tactus
