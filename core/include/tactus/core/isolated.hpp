#pragma once
// Third-party file readers (libhdf5, VTK's XML readers, OpenCV's image codecs) are not built to
// survive hostile bytes: a corrupt file can crash, hang or exhaust memory inside them. tactus
// never lets them do that to a tool: such a reader runs in a forked child process with a time
// and memory limit, and only its validated result comes back through a pipe. A crash, a hang or
// running out of memory in the child becomes one InputError naming the file; an interrupt of the
// tool stops the child too.
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

#include "tactus/core/error.hpp"

namespace tactus {

// A flat byte buffer for the child's result: values appended in order, read back in order.
class ByteWriter {
 public:
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const char*>(&v);
    bytes_.append(p, sizeof(T));
  }
  template <class T>
  void put_vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put<std::uint64_t>(v.size());
    bytes_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  void put_string(const std::string& s) {
    put<std::uint64_t>(s.size());
    bytes_ += s;
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  explicit ByteReader(const std::string& bytes) : bytes_(bytes) {}
  template <class T>
  T get() {
    T v;
    need(sizeof(T));
    std::memcpy(&v, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  template <class T>
  std::vector<T> get_vector() {
    const auto n = get<std::uint64_t>();
    if (n > (bytes_.size() - pos_) / sizeof(T)) throw Error("isolated reader: malformed result");
    std::vector<T> v(n);
    if (n) std::memcpy(v.data(), bytes_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
    return v;
  }
  std::string get_string() {
    const auto n = get<std::uint64_t>();
    need(n);
    std::string s = bytes_.substr(pos_, n);
    pos_ += n;
    return s;
  }

 private:
  void need(std::size_t n) const {
    if (n > bytes_.size() - pos_) throw Error("isolated reader: malformed result");
  }
  const std::string& bytes_;
  std::size_t pos_ = 0;
};

struct IsolationLimits {
  double seconds = 300;            // wall-clock limit of the child
  std::uint64_t memory_bytes = 0;  // address-space limit; 0: the machine's physical memory
};

// A time limit for reading a file of this size: `base` seconds plus `per_mb` per megabyte. A
// reader that loops forever on a corrupt file (VTK's XML reader does, on some) is stopped by it.
IsolationLimits limits_for_file(const std::string& file, double base = 10, double per_mb = 1);

// Runs `work` in a child process and returns what it wrote. InputErrors thrown by `work` come
// back as the same message; other exceptions, crashes, hangs and memory exhaustion become an
// InputError naming `file` and saying that this `kind` of file (e.g. "HDF5 file") is corrupt.
std::string run_isolated(const std::string& file, const std::string& kind, const std::function<void(ByteWriter&)>& work, IsolationLimits limits = {});

}  // namespace tactus
