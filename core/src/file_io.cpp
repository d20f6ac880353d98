// Checked reading and writing of files (file_io.hpp).
#include "tactus/core/file_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>

#include "tactus/core/error.hpp"

namespace fs = std::filesystem;

namespace tactus {

namespace {

constexpr std::size_t kBuffer = std::size_t{1} << 16;  // FileWriter's buffer

// A single-lane variant of xxHash64's round and avalanche (Collet 2012): 8 bytes per step, so
// hashing a results folder costs about as much as reading it.
class Hash64 {
 public:
  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    length_ += n;
    while (n > 0 && pending_ > 0 && pending_ < 8) {
      tail_[pending_++] = *p++, --n;
      if (pending_ == 8) word(tail_), pending_ = 0;
    }
    for (; n >= 8; p += 8, n -= 8) word(p);
    while (n > 0) tail_[pending_++] = *p++, --n;
  }
  std::uint64_t finish() const {
    std::uint64_t h = acc_;
    for (std::size_t i = 0; i < pending_; ++i) h = rotl(h ^ (tail_[i] * kP5), 11) * kP1;
    h ^= length_;
    h ^= h >> 33, h *= kP2, h ^= h >> 29, h *= kP3, h ^= h >> 32;
    return h;
  }
  std::string hex() const {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(finish()));
    return buf;
  }

 private:
  static constexpr std::uint64_t kP1 = 0x9E3779B185EBCA87ULL, kP2 = 0xC2B2AE3D27D4EB4FULL, kP3 = 0x165667B19E3779F9ULL, kP4 = 0x85EBCA77C2B2AE63ULL,
                                 kP5 = 0x27D4EB2F165667C5ULL;
  static std::uint64_t rotl(std::uint64_t x, int r) { return (x << r) | (x >> (64 - r)); }
  void word(const unsigned char* p) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    acc_ ^= rotl(w * kP2, 31) * kP1;
    acc_ = rotl(acc_, 27) * kP1 + kP4;
  }
  std::uint64_t acc_ = kP5, length_ = 0;
  unsigned char tail_[8]{};
  std::size_t pending_ = 0;
};

// Adds the bytes of `file` to `h`; false when it cannot be opened (nothing added).
bool hash_file_into(const fs::path& file, Hash64& h) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return false;  // never block on a FIFO
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  std::vector<char> buffer(1 << 20);
  for (;;) {
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    h.add(buffer.data(), static_cast<std::size_t>(n));
  }
  ::close(fd);
  return true;
}

}  // namespace

std::string describe_file_type(const fs::path& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    struct stat link;
    if (::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) return "a link to nothing (" + std::string(std::strerror(errno)) + ")";
    return errno == ENOENT || errno == ENOTDIR ? "no such file" : std::string("nothing readable (") + std::strerror(errno) + ")";
  }
  if (S_ISREG(st.st_mode)) return "a regular file";
  if (S_ISDIR(st.st_mode)) return "a folder";
  if (S_ISFIFO(st.st_mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(st.st_mode)) return "a character device";
  if (S_ISBLK(st.st_mode)) return "a block device";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  return "a special file";
}

std::uintmax_t require_regular_file(const fs::path& file, const std::string& what) {
  struct stat st;
  if (::stat(file.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
    const std::string found = describe_file_type(file);
    throw InputError(file.string(), "", what + (found == "no such file" ? "" : " (a regular file: tactus reads files only)"), found);
  }
  return static_cast<std::uintmax_t>(st.st_size);
}

// ---------------------------------------------------------------------------------------------
FileWriter::FileWriter(fs::path file, Mode mode) : file_(std::move(file)) {
  const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (mode == Mode::append ? O_APPEND : O_TRUNC);
  fd_ = ::open(file_.c_str(), flags, 0644);
  if (fd_ < 0) throw WriteError(file_.string(), "cannot create the file", errno);
  if (mode == Mode::append) {
    const off_t end = ::lseek(fd_, 0, SEEK_END);
    offset_ = end > 0 ? static_cast<std::uintmax_t>(end) : 0;
  }
  buffer_.reserve(kBuffer);
}

FileWriter::~FileWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void FileWriter::write(std::string_view bytes) {
  if (fd_ < 0) throw WriteError(file_.string(), "the file is closed (internal error)");
  if (buffer_.size() + bytes.size() > kBuffer) flush();
  buffer_.append(bytes);
  if (buffer_.size() >= kBuffer) flush();
}

void FileWriter::flush() {
  std::size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw WriteError(file_.string(), "writing failed", n < 0 ? errno : ENOSPC);
    done += static_cast<std::size_t>(n);
  }
  offset_ += buffer_.size();
  buffer_.clear();
}

void FileWriter::close() {
  if (fd_ < 0) return;
  flush();
  if (::fsync(fd_) != 0 && errno != EINVAL) {  // EINVAL: a file system without fsync (nothing to flush)
    const int err = errno;
    ::close(fd_), fd_ = -1;
    throw WriteError(file_.string(), "flushing it to the disk failed", err);
  }
  const int rc = ::close(fd_);
  fd_ = -1;
  if (rc != 0 && errno != EINTR) throw WriteError(file_.string(), "closing it failed", errno);
}

void write_file(const fs::path& file, std::string_view content) {
  FileWriter out(file);
  out.write(content);
  out.close();
}

namespace {
void sync_path(const fs::path& p, int flags, const std::string& what) {
  const int fd = ::open(p.c_str(), flags | O_CLOEXEC);
  if (fd < 0) throw WriteError(p.string(), "cannot reopen the " + what + " to flush it to the disk", errno);
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0 && err != EINVAL) throw WriteError(p.string(), "flushing the " + what + " to the disk failed", err);
}
}  // namespace

void sync_file(const fs::path& file) { sync_path(file, O_RDONLY, "file"); }
void sync_directory(const fs::path& folder) { sync_path(folder.empty() ? fs::path(".") : folder, O_RDONLY | O_DIRECTORY, "folder"); }

void require_tail(const fs::path& file, std::string_view tail, const std::string& what) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw WriteError(file.string(), "cannot read back what was written", errno);
  std::string end(tail.size(), '\0');
  const off_t size = ::lseek(fd, 0, SEEK_END);
  const bool ok = size >= static_cast<off_t>(tail.size()) &&
                  ::pread(fd, end.data(), tail.size(), size - static_cast<off_t>(tail.size())) == static_cast<ssize_t>(tail.size()) && end == tail;
  ::close(fd);
  if (!ok) throw_library_write_failure(file, "the " + what + " was cut short (" + std::to_string(size > 0 ? size : 0) + " bytes without its end)");
}

void throw_library_write_failure(const fs::path& file, const std::string& library_doing) {
  const int err = errno;
  if (err == ENOSPC || err == EDQUOT) throw WriteError(file.string(), library_doing, err);
  std::error_code ec;
  const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
  const fs::space_info s = fs::space(dir, ec);
  if (!ec && s.available < (std::uintmax_t{1} << 20)) throw WriteError(file.string(), library_doing, ENOSPC);
  throw WriteError(file.string(), library_doing + (err ? std::string(" (") + std::strerror(err) + ")" : std::string()));
}

std::string unique_suffix() {
  std::random_device entropy;
  const std::uint64_t r = (std::uint64_t{entropy()} << 32) ^ entropy();
  char buf[48];
  std::snprintf(buf, sizeof buf, "%ld-%016llx", static_cast<long>(::getpid()), static_cast<unsigned long long>(r));
  return buf;
}

std::string file_hash(const fs::path& file) {
  Hash64 h;
  return hash_file_into(file, h) ? h.hex() : std::string();
}

std::string content_digest(const std::vector<fs::path>& files) {
  Hash64 h;
  for (const fs::path& f : files) {  // the bytes only: the same file named another way is the same input
    const std::uint64_t separator = 0x7461637475732d2dULL;
    h.add(&separator, sizeof separator);
    if (!hash_file_into(f, h)) h.add("<missing>", 9);
  }
  return h.hex();
}

}  // namespace tactus
