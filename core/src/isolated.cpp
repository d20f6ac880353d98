#include "tactus/core/isolated.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <new>

#include "tactus/core/interrupt.hpp"

namespace tactus {

namespace {

void write_all(int fd, const char* data, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, data, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) _exit(3);
    data += w;
    n -= static_cast<std::size_t>(w);
  }
}

void send(int fd, char tag, const std::string& payload) {
  const std::uint64_t n = payload.size();
  write_all(fd, &tag, 1);
  write_all(fd, reinterpret_cast<const char*>(&n), sizeof n);
  write_all(fd, payload.data(), payload.size());
}

[[maybe_unused]] std::uint64_t physical_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(size) : 0;
}

[[noreturn]] void child(int fd, const std::function<void(ByteWriter&)>& work, const IsolationLimits& limits) {
  // Stop with the parent, and on Ctrl-C like it (the parent blocks these signals for its watcher).
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  unblock_stop_signals();
  alarm(static_cast<unsigned>(std::max(1.0, limits.seconds)));
#if !defined(__SANITIZE_ADDRESS__)
  // (AddressSanitizer reserves terabytes of address space: no limit there.)
  if (const std::uint64_t mem = limits.memory_bytes ? limits.memory_bytes : physical_memory()) {
    rlimit r{static_cast<rlim_t>(mem), static_cast<rlim_t>(mem)};
    setrlimit(RLIMIT_AS, &r);
  }
#endif
  try {
    ByteWriter w;
    work(w);
    send(fd, 'O', w.bytes());
  } catch (const InputError& e) {
    ByteWriter w;
    w.put_string(e.file());
    w.put_string(e.field());
    w.put_string(e.what());
    send(fd, 'E', w.bytes());
  } catch (const std::bad_alloc&) {
    send(fd, 'M', "");
  } catch (const std::exception& e) {
    send(fd, 'X', e.what());
  } catch (...) {
    send(fd, 'X', "unknown failure");
  }
  close(fd);
  _exit(0);
}

}  // namespace

IsolationLimits limits_for_file(const std::string& file, double base, double per_mb) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  IsolationLimits l;
  l.seconds = base + per_mb * (ec ? 0.0 : static_cast<double>(size) / 1e6);
  return l;
}

std::string run_isolated(const std::string& file, const std::string& kind, const std::function<void(ByteWriter&)>& work, IsolationLimits limits) {
  int fds[2];
  if (pipe(fds) != 0) throw Error("cannot create a pipe for the " + kind + " reader");
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]), close(fds[1]);
    throw Error("cannot start the " + kind + " reader (fork failed)");
  }
  if (pid == 0) {
    close(fds[0]);
    child(fds[1], work, limits);
  }
  close(fds[1]);
  std::string data;
  char buf[1 << 16];
  for (;;) {
    const ssize_t r = read(fds[0], buf, sizeof buf);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    data.append(buf, static_cast<std::size_t>(r));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  check_interrupt();
  const std::string corrupt = "a valid " + kind;
  if (WIFSIGNALED(status)) {
    const int s = WTERMSIG(status);
    if (s == SIGINT || s == SIGTERM || s == SIGHUP) throw Interrupted(s);  // Ctrl-C reached the child first
    if (s == SIGALRM)
      throw InputError(
          file, "", corrupt,
          "the reader did not finish within " + std::to_string(static_cast<int>(limits.seconds)) + " s (a corrupt or absurdly large file)");
    if (s == SIGKILL) throw InputError(file, "", corrupt, "the reader was killed (out of memory?)");
    throw InputError(file, "", corrupt, std::string("the reader crashed on it (") + strsignal(s) + "): the file is corrupt");
  }
  if (data.size() < 1 + sizeof(std::uint64_t))
    throw InputError(file, "", corrupt, "the reader failed (exit status " + std::to_string(WEXITSTATUS(status)) + ")");
  const char tag = data[0];
  std::uint64_t n;
  std::memcpy(&n, data.data() + 1, sizeof n);
  std::string payload = data.substr(1 + sizeof n);
  if (payload.size() != n) throw InputError(file, "", corrupt, "the reader's result was cut short");
  switch (tag) {
    case 'O':
      return payload;
    case 'E': {
      ByteReader r(payload);
      const std::string f = r.get_string(), field = r.get_string(), message = r.get_string();
      throw InputError(InputError::Formatted{}, f, field, message);
    }
    case 'M':
      throw InputError(file, "", corrupt, "it asks for more memory than this machine has (corrupt sizes?)");
    default:
      throw InputError(file, "", corrupt, "unreadable (" + payload + ")");
  }
}

}  // namespace tactus
