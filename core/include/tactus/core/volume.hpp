#pragma once
// A 3-D image volume (CT intensities or labels) on a regular grid, stored x fastest, then y,
// then z: exactly the z-y-x C-order layout of the HDF5 dataset, so I/O needs no reshuffle.
// Geometry is in metres (SI everywhere inside tactus).
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace tactus {

template <class T>
struct Volume {
  std::array<int, 3> dims{0, 0, 0};           // nx, ny, nz
  std::array<double, 3> spacing{1, 1, 1};     // m
  std::array<double, 3> origin{0, 0, 0};      // m, centre of voxel (0,0,0)
  std::vector<T> data;                        // nx*ny*nz values

  Volume() = default;
  Volume(std::array<int, 3> d, std::array<double, 3> h, std::array<double, 3> o, T fill = T{})
      : dims(d), spacing(h), origin(o),
        data(static_cast<std::size_t>(d[0]) * static_cast<std::size_t>(d[1]) *
                 static_cast<std::size_t>(d[2]),
             fill) {}

  std::size_t size() const noexcept { return data.size(); }
  std::size_t index(int x, int y, int z) const noexcept {
    return static_cast<std::size_t>(x) +
           static_cast<std::size_t>(dims[0]) *
               (static_cast<std::size_t>(y) + static_cast<std::size_t>(dims[1]) * static_cast<std::size_t>(z));
  }
  T& at(int x, int y, int z) noexcept { return data[index(x, y, z)]; }
  const T& at(int x, int y, int z) const noexcept { return data[index(x, y, z)]; }
  double voxel_volume() const noexcept { return spacing[0] * spacing[1] * spacing[2]; }
};

// Names of the labels in a label volume: 0 background, 1 soft tissue, 2.. bones.
using LabelTable = std::map<int, std::string>;

// HDF5 I/O. The dataset is z-y-x; attributes: spacing and origin (x,y,z, metres), units "m",
// and for label volumes `label_table` (JSON object id -> name). Supported voxel types:
// uint8, uint16, int16, float. Reading converts integer types when the stored values fit.
template <class T>
void write_h5(const std::filesystem::path& file, const std::string& dataset, const Volume<T>& volume,
              const LabelTable* labels = nullptr);
template <class T>
Volume<T> read_h5(const std::filesystem::path& file, const std::string& dataset,
                  LabelTable* labels = nullptr);

// VTK XML image data (.vti) for ParaView: one point-data array named `array_name`.
template <class T>
void write_vti(const std::filesystem::path& file, const Volume<T>& volume, const std::string& array_name);
template <class T>
Volume<T> read_vti(const std::filesystem::path& file, const std::string& array_name);

}  // namespace tactus
