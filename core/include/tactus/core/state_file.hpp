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
  // Loading: a checkpoint is input like any other. These refuse it (InputError naming the file and
  // the array) when a value read is not what this model allows: an index out of [lo, hi), a
  // non-finite number, a broken list of starts. Its checksum says only that the bytes are the ones
  // written, not who wrote them.
  [[noreturn]] void invalid(const std::string& name, const std::string& expected, const std::string& found) const;
  template <class V>
  void require_indices(const std::string& name, const V& v, long long lo, long long hi) const {
    for (std::size_t i = 0; i < v.size(); ++i)
      if (static_cast<long long>(v[i]) < lo || static_cast<long long>(v[i]) >= hi)
        invalid(name, "indices from " + std::to_string(lo) + " to " + std::to_string(hi - 1) + " (this model's)",
                std::to_string(static_cast<long long>(v[i])) + " at position " + std::to_string(i));
  }
  // Starts of a compressed list: `count` + 1 non-decreasing values from 0 (or, empty, no list yet) to at most `items`.
  template <class V>
  void require_starts(const std::string& name, const V& start, std::size_t count, std::size_t items) const {
    if (start.empty()) return;
    if (start.size() != count + 1) size_error(name, count + 1, start.size());
    for (std::size_t i = 0; i < start.size(); ++i)
      if (static_cast<long long>(start[i]) < (i ? static_cast<long long>(start[i - 1]) : 0) || static_cast<std::size_t>(start[i]) > items)
        invalid(name, "non-decreasing list starts from 0 to " + std::to_string(items),
                std::to_string(static_cast<long long>(start[i])) + " at position " + std::to_string(i));
  }
  void require_finite(const std::string& name, const std::vector<double>& v) const;
  void require_finite(const std::string& name, double x) const { require_finite(name, std::vector<double>{x}); }
  const std::string& file() const { return file_; }

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
