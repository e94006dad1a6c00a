// Output files that appear complete or not at all.
//
// AtomicFile writes to a temporary file created next to the target (same directory,
// so the final rename(2) never crosses a file system) and renames it onto the target
// only in commit(). Destroying an AtomicFile that was not committed removes the
// temporary file, so a run that fails or throws half way leaves no partial output and
// any previous version of the target untouched. POSIX only (mkstemp, rename).
//
// The target must be a regular file or a path that does not exist yet: the rename
// replaces whatever the path names, so a FIFO, a device, a directory or a symbolic link
// there is refused (OutputTargetError, checked when the AtomicFile is created and again
// just before the rename) instead of being replaced by a regular file.
#pragma once

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace inhand::examples {

/// The path given for an output names something that is not a regular file.
class OutputTargetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What lstat(2) says `path` is, for messages ("directory", "FIFO", ...).
inline std::string file_type_name(const struct stat& st) {
  if (S_ISREG(st.st_mode)) return "regular file";
  if (S_ISDIR(st.st_mode)) return "directory";
  if (S_ISLNK(st.st_mode)) return "symbolic link";
  if (S_ISFIFO(st.st_mode)) return "FIFO";
  if (S_ISCHR(st.st_mode)) return "character device";
  if (S_ISBLK(st.st_mode)) return "block device";
  if (S_ISSOCK(st.st_mode)) return "socket";
  return "special file";
}

/// Throws OutputTargetError unless `path` is a regular file or does not exist (the
/// path itself, not what a symbolic link there points to). Other lstat(2) failures
/// (a missing directory, no permission) are left to the file creation to report.
inline void check_output_target(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0 || S_ISREG(st.st_mode)) return;
  std::string what = file_type_name(st);
  if (S_ISLNK(st.st_mode)) {
    std::vector<char> buf(4096);
    const ssize_t n = ::readlink(path.c_str(), buf.data(), buf.size() - 1);
    if (n >= 0) what += " to " + std::string(buf.data(), static_cast<std::size_t>(n));
  }
  throw OutputTargetError(path + ": is a " + what +
                          ", not a regular file (outputs are written only to regular files or "
                          "new paths)");
}

class AtomicFile {
 public:
  /// Creates the temporary file "<dir>/.<name>.XXXXXX"; throws OutputTargetError when
  /// the target is not a regular file (check_output_target), std::runtime_error when
  /// the temporary file cannot be created (missing directory, no permission).
  explicit AtomicFile(std::string path) : path_(std::move(path)) {
    check_output_target(path_);
    const std::size_t slash = path_.find_last_of('/');
    const std::string dir = slash == std::string::npos ? std::string() : path_.substr(0, slash + 1);
    const std::string base = slash == std::string::npos ? path_ : path_.substr(slash + 1);
    if (base.empty()) throw std::runtime_error(path_ + ": not a file name");
    std::string templ = dir + "." + base + ".XXXXXX";
    std::vector<char> buf(templ.begin(), templ.end());
    buf.push_back('\0');
    const int fd = ::mkstemp(buf.data());
    if (fd < 0)
      throw std::runtime_error(path_ + ": cannot create a temporary file: " + std::strerror(errno));
    temp_.assign(buf.data());
    // mkstemp creates the file 0600; outputs get the usual 0666 & ~umask.
    const mode_t mask = ::umask(0);
    ::umask(mask);
    ::fchmod(fd, static_cast<mode_t>(0666) & ~mask);
    file_ = ::fdopen(fd, "w");
    if (file_ == nullptr) {
      ::close(fd);
      ::unlink(temp_.c_str());
      throw std::runtime_error(path_ + ": cannot open the temporary file");
    }
  }
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile() { discard(); }

  /// The stream to write to (valid until commit() or discard()).
  std::FILE* stream() const noexcept { return file_; }
  const std::string& path() const noexcept { return path_; }

  void write(const std::string& text) {
    if (file_ == nullptr) throw std::logic_error(path_ + ": already closed");
    if (std::fwrite(text.data(), 1, text.size(), file_) != text.size())
      throw std::runtime_error(path_ + ": write failed");
  }

  /// Flushes, closes and renames the temporary file onto the target. Throws on any I/O
  /// error, and OutputTargetError when the target has meanwhile become something other
  /// than a regular file (the temporary file is then removed).
  void commit() {
    if (file_ == nullptr) throw std::logic_error(path_ + ": already closed");
    const bool write_error = std::ferror(file_) != 0;
    const bool close_error = std::fclose(file_) != 0;
    file_ = nullptr;
    if (write_error || close_error) {
      ::unlink(temp_.c_str());
      temp_.clear();
      throw std::runtime_error(path_ + ": write failed");
    }
    try {
      check_output_target(path_);
    } catch (...) {
      ::unlink(temp_.c_str());
      temp_.clear();
      throw;
    }
    if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
      const int err = errno;
      ::unlink(temp_.c_str());
      temp_.clear();
      throw std::runtime_error(path_ + ": cannot rename the temporary file: " + std::strerror(err));
    }
    temp_.clear();
  }

  /// Drops everything written so far (no-op after commit()).
  void discard() noexcept {
    if (file_ != nullptr) {
      std::fclose(file_);
      file_ = nullptr;
    }
    if (!temp_.empty()) {
      ::unlink(temp_.c_str());
      temp_.clear();
    }
  }

 private:
  std::string path_;
  std::string temp_;
  std::FILE* file_ = nullptr;
};

/// Writes `text` to `path` atomically.
inline void write_file_atomically(const std::string& path, const std::string& text) {
  AtomicFile f(path);
  f.write(text);
  f.commit();
}

}  // namespace inhand::examples
