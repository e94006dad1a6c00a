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
//
// Several outputs of one run appear together: commit_together() completes every
// temporary file before it renames any, and removes the ones it renamed if a later
// rename fails. A program that calls remove_temporaries_on_signals() also loses no
// temporary file to SIGINT, SIGTERM or SIGHUP: the handler removes the temporary files
// of the AtomicFiles alive (and the directory given to remove_directory_on_signals(),
// if it is empty), then the program dies of the signal as it would have. Creation,
// renames and removal run with those signals blocked, so a signal sees a consistent
// set of temporary files and falls between two complete commits, never inside one.
#pragma once

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
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

namespace detail {

/// Temporary files alive (pointers to their names, owned by the AtomicFiles) and one
/// directory, read by the signal handler: lock-free atomics, no allocation there.
constexpr std::size_t kMaxTemporaries = 16;
inline std::atomic<const char*> temporaries[kMaxTemporaries];
inline std::atomic<const char*> directory_to_remove{nullptr};

/// Blocks SIGINT, SIGTERM and SIGHUP for its lifetime (the example programs are single
/// threaded; sigprocmask is the process mask then).
class TerminationSignalsBlocked {
 public:
  TerminationSignalsBlocked() {
    sigset_t set = termination_signals();
    ::sigprocmask(SIG_BLOCK, &set, &old_);
  }
  TerminationSignalsBlocked(const TerminationSignalsBlocked&) = delete;
  TerminationSignalsBlocked& operator=(const TerminationSignalsBlocked&) = delete;
  ~TerminationSignalsBlocked() { ::sigprocmask(SIG_SETMASK, &old_, nullptr); }

  static sigset_t termination_signals() {
    sigset_t set;
    sigemptyset(&set);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&set, sig);
    return set;
  }

 private:
  sigset_t old_{};
};

/// Registers a temporary file for the signal handler; false when all slots are taken.
inline bool add_temporary(const char* path) noexcept {
  for (auto& slot : temporaries) {
    const char* expected = nullptr;
    if (slot.compare_exchange_strong(expected, path)) return true;
  }
  return false;
}
inline void forget_temporary(const char* path) noexcept {
  for (auto& slot : temporaries) {
    const char* expected = path;
    slot.compare_exchange_strong(expected, nullptr);
  }
}

/// Only async-signal-safe calls (unlink, rmdir, signal, raise) on precomputed paths.
inline void remove_temporaries_and_reraise(int sig) {
  const int saved_errno = errno;
  for (auto& slot : temporaries)
    if (const char* p = slot.load()) ::unlink(p);
  if (const char* d = directory_to_remove.load()) ::rmdir(d);  // only if empty
  ::signal(sig, SIG_DFL);
  ::raise(sig);  // delivered with the default action when the handler returns
  errno = saved_errno;
}

}  // namespace detail

/// Installs the handler that removes the temporary files of live AtomicFiles on SIGINT,
/// SIGTERM and SIGHUP and then dies of the signal. A signal ignored when this is called
/// (nohup, background jobs of a shell) stays ignored.
inline void remove_temporaries_on_signals() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    struct sigaction sa {};
    sa.sa_handler = detail::remove_temporaries_and_reraise;
    sa.sa_mask = detail::TerminationSignalsBlocked::termination_signals();
    ::sigaction(sig, &sa, nullptr);
  }
}

/// Makes the handler of remove_temporaries_on_signals() also remove `dir` (rmdir(2):
/// only when it is empty then); nullptr forgets it. `dir` must outlive the registration.
inline void remove_directory_on_signals(const char* dir) noexcept {
  detail::directory_to_remove.store(dir);
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
    detail::TerminationSignalsBlocked blocked;
    const int fd = ::mkstemp(buf.data());
    if (fd < 0)
      throw std::runtime_error(path_ + ": cannot create a temporary file: " + std::strerror(errno));
    temp_.assign(buf.data());
    if (!detail::add_temporary(temp_.c_str())) {
      ::close(fd);
      remove_temporary();
      throw std::runtime_error(path_ + ": too many output files at once");
    }
    // mkstemp creates the file 0600; outputs get the usual 0666 & ~umask.
    const mode_t mask = ::umask(0);
    ::umask(mask);
    ::fchmod(fd, static_cast<mode_t>(0666) & ~mask);
    file_ = ::fdopen(fd, "w");
    if (file_ == nullptr) {
      ::close(fd);
      remove_temporary();
      throw std::runtime_error(path_ + ": cannot open the temporary file");
    }
  }
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile() { discard(); }

  /// The stream to write to (valid until finish(), commit() or discard()).
  std::FILE* stream() const noexcept { return file_; }
  const std::string& path() const noexcept { return path_; }

  void write(const std::string& text) {
    if (file_ == nullptr) throw std::logic_error(path_ + ": already closed");
    if (std::fwrite(text.data(), 1, text.size(), file_) != text.size())
      throw std::runtime_error(path_ + ": write failed");
  }

  /// Flushes and closes the temporary file, which is then complete but not yet renamed.
  /// Throws on any I/O error (the temporary file is then removed).
  void finish() {
    if (file_ == nullptr) throw std::logic_error(path_ + ": already closed");
    const bool write_error = std::ferror(file_) != 0;
    const bool close_error = std::fclose(file_) != 0;
    file_ = nullptr;
    if (write_error || close_error) {
      remove_temporary();
      throw std::runtime_error(path_ + ": write failed");
    }
  }

  /// finish() (unless done) and renames the temporary file onto the target. Throws on
  /// any I/O error, and OutputTargetError when the target has meanwhile become
  /// something other than a regular file (the temporary file is then removed).
  void commit() {
    if (file_ != nullptr) finish();
    check_target_or_discard();
    rename_onto_target();
  }

  /// Drops everything written so far (no-op after commit()).
  void discard() noexcept {
    if (file_ != nullptr) {
      std::fclose(file_);
      file_ = nullptr;
    }
    remove_temporary();
  }

 private:
  friend void commit_together(std::initializer_list<AtomicFile*> files);

  void check_target_or_discard() {
    if (temp_.empty()) throw std::logic_error(path_ + ": already committed or discarded");
    try {
      check_output_target(path_);
    } catch (...) {
      discard();
      throw;
    }
  }
  void rename_onto_target() {
    detail::TerminationSignalsBlocked blocked;
    if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
      const int err = errno;
      remove_temporary();
      throw std::runtime_error(path_ + ": cannot rename the temporary file: " + std::strerror(err));
    }
    detail::forget_temporary(temp_.c_str());
    temp_.clear();
  }
  void remove_temporary() noexcept {
    if (temp_.empty()) return;
    detail::TerminationSignalsBlocked blocked;
    ::unlink(temp_.c_str());
    detail::forget_temporary(temp_.c_str());
    temp_.clear();
  }

  std::string path_;
  std::string temp_;
  std::FILE* file_ = nullptr;
};

/// Commits all `files` or none: every one is finished and its target checked before
/// the first rename; if a rename still fails (the file system changed meanwhile), the
/// targets renamed before it are removed again (their previous versions are gone then)
/// and the rest discarded, then the error is thrown. Null pointers are skipped. Termination signals
/// wait until all renames are done.
inline void commit_together(std::initializer_list<AtomicFile*> files) {
  try {
    for (AtomicFile* f : files)
      if (f != nullptr && f->file_ != nullptr) f->finish();
    for (AtomicFile* f : files)
      if (f != nullptr) f->check_target_or_discard();
  } catch (...) {
    for (AtomicFile* f : files)
      if (f != nullptr) f->discard();
    throw;
  }
  detail::TerminationSignalsBlocked blocked;
  std::vector<const std::string*> renamed;
  for (AtomicFile* f : files) {
    if (f == nullptr) continue;
    try {
      f->rename_onto_target();
    } catch (...) {
      for (const std::string* p : renamed) ::unlink(p->c_str());
      for (AtomicFile* g : files)
        if (g != nullptr) g->discard();
      throw;
    }
    renamed.push_back(&f->path());
  }
}

/// Writes `text` to `path` atomically.
inline void write_file_atomically(const std::string& path, const std::string& text) {
  AtomicFile f(path);
  f.write(text);
  f.commit();
}

}  // namespace inhand::examples
