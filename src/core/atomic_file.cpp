// Safe output files (README.md, "Errors and output files"):
// - the target must be absent or a regular file: a symlink, directory, device or FIFO is refused
//   (a report written with root rights must not replace /dev/sda or follow a planted link);
// - the data goes to a temporary file created with O_CREAT|O_EXCL|O_NOFOLLOW in the target's
//   folder (never an existing file or a link), named ".<name>.adamesh-tmp-<pid>-<n>", then is
//   renamed over the target: readers see the old file or the complete new one;
// - temporaries of the same target left by a process that no longer exists (kill -9, power
//   loss) are removed before a new one is created; live processes' temporaries are left alone.
#include "adamesh/atomic_file.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <streambuf>
#include <vector>

#include "adamesh/error.h"

namespace adamesh {

namespace {

[[noreturn]] void fail_output(const std::string& path, const std::string& what) {
  fail(Status::output_failed, path + ": " + what);
}

std::string errno_text(int err) { return std::strerror(err); }

/// "dir/", "" for the current folder; and the file's own name.
void split_path(const std::string& path, std::string& dir, std::string& name) {
  const std::size_t slash = path.find_last_of('/');
  dir = slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
  name = slash == std::string::npos ? path : path.substr(slash + 1);
}

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

/// Removes "<prefix><pid>-<n>" entries of `dir` whose pid is not a running process.
void remove_stale_temporaries(const std::string& dir, const std::string& prefix) {
  DIR* d = ::opendir(dir.empty() ? "." : dir.c_str());
  if (!d) return;
  std::vector<std::string> stale;
  while (const dirent* e = ::readdir(d)) {
    const std::string n = e->d_name;
    if (n.compare(0, prefix.size(), prefix) != 0) continue;
    char* end = nullptr;
    const long pid = std::strtol(n.c_str() + prefix.size(), &end, 10);
    if (pid <= 0 || end == nullptr || *end != '-') continue;
    if (pid == ::getpid()) continue;  // our own (another thread's write)
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive, or unknown
    stale.push_back(n);
  }
  ::closedir(d);
  for (const auto& n : stale) {
    struct stat st {};
    // Only regular files: the name pattern is ours, but never remove anything else.
    if (::lstat((dir + n).c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::unlink((dir + n).c_str());
  }
}

/// Buffered std::streambuf over a file descriptor; errors are remembered, not thrown.
class FdBuf : public std::streambuf {
 public:
  explicit FdBuf(int fd) : fd_(fd), buf_(1 << 16) { setp(buf_.data(), buf_.data() + buf_.size()); }
  ~FdBuf() override = default;
  int error() const { return error_; }

 protected:
  int_type overflow(int_type ch) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(ch, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(ch);
      pbump(1);
    }
    return traits_type::not_eof(ch);
  }
  int sync() override { return drain() ? 0 : -1; }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (n >= static_cast<std::streamsize>(buf_.size())) {  // large blocks bypass the buffer
      if (!drain() || !write_all(s, static_cast<std::size_t>(n))) return 0;
      return n;
    }
    return std::streambuf::xsputn(s, n);
  }

 private:
  bool write_all(const char* p, std::size_t n) {
    while (n > 0) {
      const ssize_t w = ::write(fd_, p, n);
      if (w < 0) {
        if (errno == EINTR) continue;
        error_ = errno;
        return false;
      }
      p += w;
      n -= static_cast<std::size_t>(w);
    }
    return true;
  }
  bool drain() {
    if (error_) return false;
    const std::size_t n = static_cast<std::size_t>(pptr() - pbase());
    setp(buf_.data(), buf_.data() + buf_.size());
    return write_all(buf_.data(), n);
  }
  int fd_;
  std::vector<char> buf_;
  int error_ = 0;
};

}  // namespace

std::string temporary_file_prefix(const std::string& target_name) {
  return "." + target_name + ".adamesh-tmp-";
}

void check_output_target(const std::string& path) {
  if (path.empty()) fail(Status::output_failed, "empty output path");
  std::string dir, name;
  split_path(path, dir, name);
  if (name.empty() || name == "." || name == "..")
    fail_output(path, "names a directory, not a file");
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode))
      fail_output(path, std::string("is ") + kind_of(st.st_mode) +
                            "; adamesh writes regular files only (remove it or choose another name)");
  } else if (errno != ENOENT) {
    fail_output(path, "cannot inspect: " + errno_text(errno));
  }
  const std::string folder = dir.empty() ? "." : dir;
  struct stat ds {};
  if (::stat(folder.c_str(), &ds) != 0)
    fail_output(path, "folder " + folder + (errno == ENOENT ? " does not exist" : ": " + errno_text(errno)));
  if (!S_ISDIR(ds.st_mode)) fail_output(path, folder + " is not a folder");
  if (::access(folder.c_str(), W_OK | X_OK) != 0)
    fail_output(path, "folder " + folder + " is not writable: " + errno_text(errno));
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool /*binary: POSIX files make no difference*/) {
  check_output_target(path);
  std::string dir, name;
  split_path(path, dir, name);
  const std::string prefix = temporary_file_prefix(name);
  remove_stale_temporaries(dir, prefix);

  static std::atomic<unsigned> counter{0};
  std::string tmp;
  int fd = -1;
  for (int attempt = 0; fd < 0; ++attempt) {
    tmp = dir + prefix + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    // O_EXCL|O_NOFOLLOW: never an existing file, never through a link planted under this name.
    fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd < 0 && (errno != EEXIST || attempt >= 100))
      fail_output(path, "cannot create a temporary file in " + (dir.empty() ? std::string(".") : dir) +
                            ": " + errno_text(errno));
  }
  struct Cleanup {
    const std::string& name;
    int fd;
    bool armed = true;
    ~Cleanup() {
      if (fd >= 0) ::close(fd);
      if (armed) ::unlink(name.c_str());
    }
  } cleanup{tmp, fd};

  {
    FdBuf buf(fd);
    std::ostream out(&buf);
    write(out);
    out.flush();
    if (!out || buf.error())
      fail_output(path, "write failed: " + errno_text(buf.error() ? buf.error() : EIO));
  }
  const int fd_to_close = cleanup.fd;
  cleanup.fd = -1;
  if (::close(fd_to_close) != 0) fail_output(path, "closing the file failed: " + errno_text(errno));
  // The target may have changed since check_output_target (a race): rename never follows a
  // symlink at the target name (it replaces the link), and refuses to replace a directory.
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    fail_output(path, std::string("is ") + kind_of(st.st_mode) + "; adamesh writes regular files only");
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    fail_output(path, "cannot rename the temporary file: " + errno_text(errno));
  cleanup.armed = false;
}

}  // namespace adamesh
