#pragma once
// RAII for libhdf5 identifiers and its error printing (private to core: volume_io.cpp, state_file.cpp).
#include <hdf5.h>

#include <string>

namespace tactus {

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
  // Closes now and says whether that worked (a file's close writes its last metadata: on a full
  // disk it is where the failure shows).
  bool close() {
    const herr_t rc = id_ >= 0 ? closer_(id_) : 0;
    id_ = -1;
    return rc >= 0;
  }

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

// A fixed-length string attribute.
void write_string_attribute(hid_t obj, const char* name, const std::string& value);
// A string attribute of any kind HDF5 stores; "" when absent; InputError naming file and
// where@name when it is not a single string.
std::string read_string_attribute(hid_t obj, const char* name, const std::string& file, const std::string& where);

}  // namespace tactus
