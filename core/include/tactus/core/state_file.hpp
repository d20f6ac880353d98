#pragma once
// A checkpoint's container (tactus-solve's restart files): named arrays of reals, integers and raw
// records in one HDF5 file. Written atomically: under a temporary name next to the final one,
// closed, flushed to the disk (fsync) and renamed, so a file under its final name is always
// complete. Read back by libhdf5 in an isolated child process (isolated.hpp: hostile bytes never
// reach the tool) and checked against a checksum of every array stored with them, so a truncated
// or corrupt file is refused with one message naming it, never half-read.
//
// StateArchive is how a component (the integrator, the contact solver, the run loop) describes
// what it saves: one `io(name, value)` per member serves both directions, so what is written and
// what is read back cannot drift apart.
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "tactus/core/error.hpp"

namespace tactus {

struct StateArrays {
  std::map<std::string, std::vector<double>> reals;           // HDF5 64-bit floats
  std::map<std::string, std::vector<std::int64_t>> integers;  // HDF5 64-bit integers
  std::map<std::string, std::string> records;                 // HDF5 bytes: packed structs, text
  std::string kind;                                           // what the file holds, e.g. "tactus-solve checkpoint"
};

// `phase` (may be empty) is told "data" once the arrays are in the temporary file (still open),
// "written" once it is closed and on the disk, and "renamed" once it has its final name: the
// restart tests stop the process at each of them.
void write_state_file(const std::filesystem::path& file, const StateArrays& state, const std::function<void(const char*)>& phase = {});
// InputError naming the file when it is missing, not HDF5, truncated, of another kind, or when
// its arrays do not match their checksum.
StateArrays read_state_file(const std::filesystem::path& file, const std::string& kind);

// A digest (64-bit FNV-1a, hex) of the files' bytes in order (not their names), to tell whether
// inputs changed; a missing file counts as "<missing>".
std::string content_digest(const std::vector<std::filesystem::path>& files);

class StateArchive {
 public:
  static constexpr std::size_t kAnySize = std::numeric_limits<std::size_t>::max();
  // Saving: io() copies values into arrays().
  StateArchive() = default;
  // Loading: io() takes values out of `loaded` (read from `file`, named in errors).
  StateArchive(StateArrays loaded, std::string file) : arrays_(std::move(loaded)), file_(std::move(file)), loading_(true) {}
  bool loading() const { return loading_; }
  StateArrays& arrays() { return arrays_; }

  // A loaded array must have `size` entries (kAnySize: any).
  void io(const std::string& name, std::vector<double>& v, std::size_t size = kAnySize);
  void io(const std::string& name, std::vector<std::int32_t>& v, std::size_t size = kAnySize);
  void io(const std::string& name, std::vector<std::int64_t>& v, std::size_t size = kAnySize);
  void io(const std::string& name, std::vector<std::size_t>& v, std::size_t size = kAnySize);
  void io(const std::string& name, double& x);
  void io(const std::string& name, std::string& text);
  template <class T>
  requires std::is_integral_v<T>
  void io(const std::string& name, T& x) {
    std::vector<std::int64_t> v{static_cast<std::int64_t>(x)};
    io(name, v, 1);
    x = static_cast<T>(v[0]);
  }
  // Trivially copyable records (a struct of numbers), stored as their bytes: only the binary that
  // wrote them reads them (the checkpoint records the version).
  template <class T>
  void io_records(const std::string& name, std::vector<T>& v, std::size_t size = kAnySize) {
    static_assert(std::is_trivially_copyable_v<T>);
    std::string bytes;
    if (!loading_) bytes.assign(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    io(name, bytes);
    if (!loading_) return;
    if (bytes.size() % sizeof(T) != 0 || (size != kAnySize && bytes.size() != size * sizeof(T))) size_error(name, size * sizeof(T), bytes.size());
    v.resize(bytes.size() / sizeof(T));
    if (!bytes.empty()) std::memcpy(static_cast<void*>(v.data()), bytes.data(), bytes.size());
  }
  template <class T>
  void io_record(const std::string& name, T& x) {
    std::vector<T> v{x};
    io_records(name, v, 1);
    x = v[0];
  }

 private:
  template <class Stored, class T>
  void io_array(std::map<std::string, std::vector<Stored>>& map, const std::string& name, std::vector<T>& v, std::size_t size);
  [[noreturn]] void size_error(const std::string& name, std::size_t expected, std::size_t found) const;
  [[noreturn]] void missing(const std::string& name) const;
  StateArrays arrays_;
  std::string file_;
  bool loading_ = false;
};

}  // namespace tactus
