#pragma once
// A 3-D image volume (CT intensities or labels) on a regular grid, stored x fastest, then y,
// then z: exactly the z-y-x C-order layout of the HDF5 dataset, so I/O needs no reshuffle.
// Geometry is in metres (SI everywhere inside tactus).
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace tactus {

// The orientation of a volume's axes in the world (patient) frame: a 3x3 rotation (or rotation
// with a reflection) stored row by row, whose column a is the world direction of voxel axis a.
// A voxel (i, j, k) lies at origin + D (i dx, j dy, k dz). World coordinates follow DICOM's
// patient frame (LPS: x to the patient's left, y posterior, z superior); readers of formats in
// other frames (NIfTI's RAS) convert.
using Direction = std::array<double, 9>;
inline constexpr Direction kIdentityDirection{1, 0, 0, 0, 1, 0, 0, 0, 1};

template <class T>
struct Volume {
  std::array<int, 3> dims{0, 0, 0};        // nx, ny, nz
  std::array<double, 3> spacing{1, 1, 1};  // m
  std::array<double, 3> origin{0, 0, 0};   // m, centre of voxel (0,0,0)
  Direction direction = kIdentityDirection;
  std::vector<T> data;  // nx*ny*nz values

  Volume() = default;
  Volume(std::array<int, 3> d, std::array<double, 3> h, std::array<double, 3> o, T fill = T{})
      : dims(d),
        spacing(h),
        origin(o),
        data(static_cast<std::size_t>(d[0]) * static_cast<std::size_t>(d[1]) * static_cast<std::size_t>(d[2]), fill) {}

  std::size_t size() const noexcept { return data.size(); }
  std::size_t index(int x, int y, int z) const noexcept {
    return static_cast<std::size_t>(x) +
           static_cast<std::size_t>(dims[0]) * (static_cast<std::size_t>(y) + static_cast<std::size_t>(dims[1]) * static_cast<std::size_t>(z));
  }
  T& at(int x, int y, int z) noexcept { return data[index(x, y, z)]; }
  const T& at(int x, int y, int z) const noexcept { return data[index(x, y, z)]; }
  double voxel_volume() const noexcept { return spacing[0] * spacing[1] * spacing[2]; }
  // The world position of a point given in the axis-aligned frame (origin + index * spacing).
  std::array<double, 3> to_world(const std::array<double, 3>& aligned) const noexcept {
    const double d[3] = {aligned[0] - origin[0], aligned[1] - origin[1], aligned[2] - origin[2]};
    std::array<double, 3> w{};
    for (int r = 0; r < 3; ++r) w[r] = origin[r] + direction[3 * r] * d[0] + direction[3 * r + 1] * d[1] + direction[3 * r + 2] * d[2];
    return w;
  }
  // The world position of the centre of the voxel at flat index `v` (x fastest).
  std::array<double, 3> voxel_world(std::size_t v) const noexcept {
    const std::size_t nx = static_cast<std::size_t>(dims[0]), ny = static_cast<std::size_t>(dims[1]);
    return to_world({origin[0] + spacing[0] * static_cast<double>(v % nx), origin[1] + spacing[1] * static_cast<double>(v / nx % ny),
                     origin[2] + spacing[2] * static_cast<double>(v / (nx * ny))});
  }
  // The same geometry (dims, spacing, origin, direction) with every voxel `fill`.
  template <class U>
  Volume<U> like(U fill = U{}) const {
    Volume<U> v(dims, spacing, origin, fill);
    v.direction = direction;
    return v;
  }
};

inline bool is_identity(const Direction& d) {
  for (int i = 0; i < 9; ++i)
    if (std::abs(d[i] - kIdentityDirection[i]) > 1e-12) return false;
  return true;
}
inline double determinant(const Direction& d) {
  return d[0] * (d[4] * d[8] - d[5] * d[7]) - d[1] * (d[3] * d[8] - d[5] * d[6]) + d[2] * (d[3] * d[7] - d[4] * d[6]);
}
// Throws InputError (naming `file` and `field`) unless d is orthonormal within 1e-4 (DICOM and
// NIfTI store cosines to ~6 digits).
void validate_direction(const Direction& d, const std::string& file, const std::string& field);

// Names of the labels in a label volume: 0 background, 1 soft tissue, 2.. bones.
using LabelTable = std::map<int, std::string>;
// A label's name in messages: the table's, else "background" for 0, else "label <id>".
inline std::string label_name(const LabelTable& table, int id) {
  const auto it = table.find(id);
  return it != table.end() ? it->second : id == 0 ? std::string("background") : "label " + std::to_string(id);
}

// Limits of what tactus accepts as a volume: voxels per axis, and the plausible physical range of
// a voxel (0.1 um to 1 m) and of an origin (within 1 km).
inline constexpr int kMaxVolumeDim = 65536;
inline constexpr double kMinSpacing = 1e-7, kMaxSpacing = 1.0, kMaxOrigin = 1e3;

// Throws InputError (naming `file` and `field`) unless the dims are 1..kMaxVolumeDim, the
// spacings finite within [kMinSpacing, kMaxSpacing], the origin finite within kMaxOrigin, and the
// voxels (of `bytes_per_voxel`) fit in half this machine's memory.
void validate_volume_geometry(const std::array<int, 3>& dims, const std::array<double, 3>& spacing, const std::array<double, 3>& origin,
                              std::size_t bytes_per_voxel, const std::string& file, const std::string& field);

// The label table stored with label volumes: a JSON object {"id": "name"} with ids 0..65535.
LabelTable parse_label_table(const std::string& json_text, const std::string& file, const std::string& field);

// HDF5 I/O. The dataset is z-y-x; attributes: spacing and origin (x,y,z, metres), units "m",
// and for label volumes `label_table` (JSON object id -> name). Supported voxel types:
// uint8, uint16, int16, float. Reading converts integer types when every stored value fits (a
// value that does not is an error, never clamped). The HDF5 and VTK readers run in an isolated
// child process (isolated.hpp): a corrupt file is an InputError, never a crash.
template <class T>
void write_h5(const std::filesystem::path& file, const std::string& dataset, const Volume<T>& volume, const LabelTable* labels = nullptr);
template <class T>
Volume<T> read_h5(const std::filesystem::path& file, const std::string& dataset, LabelTable* labels = nullptr);

// VTK XML image data (.vti) for ParaView: one point-data array named `array_name`.
template <class T>
void write_vti(const std::filesystem::path& file, const Volume<T>& volume, const std::string& array_name);
template <class T>
Volume<T> read_vti(const std::filesystem::path& file, const std::string& array_name);

}  // namespace tactus
