#pragma once
// Files as tactus reads and writes them, with every failure seen.
//
// Reading: an input must be a regular file once links are resolved. A FIFO, a device such as
// /dev/zero or /dev/urandom, a folder or a socket is refused by name before anything opens it:
// such a "file" blocks forever or never ends, and would hang any reader, ours or a third party's.
//
// Writing: FileWriter checks every write(2), then fsync(2) and close(2). A full disk is reported as
// "no space left on device" (WriteError::no_space()), never as a short file that looks complete.
// Third-party writers (VTK, gmsh, HDF5) that may not report a failed write have their file checked
// afterwards (require_tail) and flushed to the disk (sync_file) before tactus publishes it.
//
// Content hashes: the output manifests record one per file (output.hpp), so a file a user edited
// is told apart from the one tactus wrote whatever its size and modification time.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace tactus {

// The file's size; InputError naming `file` when it is missing or not a regular file. `what` says
// what the file was to be, e.g. "a mesh (.msh)".
std::uintmax_t require_regular_file(const std::filesystem::path& file, const std::string& what);
// What is at `path`, in words ("a folder", "a FIFO (named pipe)", "a character device", ...),
// following links; "no such file" when nothing is there.
std::string describe_file_type(const std::filesystem::path& path);

class FileWriter {
 public:
  enum class Mode { truncate, append };
  // Opens (creates) `file` for writing; WriteError naming it when it cannot.
  explicit FileWriter(std::filesystem::path file, Mode mode = Mode::truncate);
  ~FileWriter();  // closes without the checks when close() was not called (the caller is unwinding)
  FileWriter(const FileWriter&) = delete;
  FileWriter& operator=(const FileWriter&) = delete;

  void write(std::string_view bytes);  // buffered; a failed write(2) throws WriteError
  FileWriter& operator<<(std::string_view s) {
    write(s);
    return *this;
  }
  void flush();  // hands the buffer to the system (checked)
  // Bytes written so far (in the file after flush()).
  std::uintmax_t size() const noexcept { return offset_ + buffer_.size(); }
  // Flushes, fsyncs and closes, each checked.
  void close();
  const std::filesystem::path& path() const noexcept { return file_; }

 private:
  std::filesystem::path file_;
  int fd_ = -1;
  std::string buffer_;
  std::uintmax_t offset_ = 0;
};

// The whole file at once: created or truncated, written, flushed to the disk, closed; all checked.
void write_file(const std::filesystem::path& file, std::string_view content);
// fsync of an existing file, or of a folder (its entries: a rename on the disk), checked.
void sync_file(const std::filesystem::path& file);
void sync_directory(const std::filesystem::path& folder);
// WriteError unless `file` ends with `tail`: a third-party writer's output cut short (a full disk
// it did not report) is caught before it is published. `what` names the format.
void require_tail(const std::filesystem::path& file, std::string_view tail, const std::string& what);

// "<pid>-<16 random hex digits>": a name no other process picks, even one with the same pid in
// another PID namespace.
std::string unique_suffix();

// The error of a third-party writer (HDF5, VTK, gmsh) that failed on `file`: "no space left on
// device" when errno or the free space on that file system says so (WriteError::no_space()),
// else `library` and what it was doing. Read errno right after the failing call.
[[noreturn]] void throw_library_write_failure(const std::filesystem::path& file, const std::string& library_doing);

// A 64-bit hash (hex) of a file's bytes, or "" when it cannot be read. Not cryptographic: it tells
// whether a file changed, as a user's edit or another program's write would change it.
std::string file_hash(const std::filesystem::path& file);
// One hash over the bytes of several files in order (not their names), to tell whether inputs
// changed; a missing file counts as "<missing>".
std::string content_digest(const std::vector<std::filesystem::path>& files);

}  // namespace tactus
