#include "truecut/rt/atomic_write.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

namespace truecut::rt {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const fs::path& path, const std::string& what, int err) {
  throw FileWriteError(path, what + ": " + std::strerror(err));
}

void write_all(int fd, std::string_view bytes, const fs::path& file) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(file, "cannot write", n < 0 ? errno : EIO);
    done += static_cast<std::size_t>(n);
  }
}

// Creates (or truncates) the regular file `file` for writing. Never follows
// a symbolic link and never opens a FIFO or device that happens to carry the
// name.
int open_new_file(const fs::path& file) {
  const int fd = ::open(file.c_str(),
                        O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0644);
  if (fd < 0) fail(file, "cannot create", errno);
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw FileWriteError(file, "exists and is not a regular file; not used");
  }
  return fd;
}

// Syncs and closes `fd` (the file `file`); on failure removes the file.
void sync_and_close(int fd, const fs::path& file) {
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    ::unlink(file.c_str());
    fail(file, "cannot sync", err);
  }
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(file.c_str());
    fail(file, "cannot close", err);
  }
}

// The regular file `file` with `bytes`, synced; removed again on failure.
void write_new_file(const fs::path& file, std::string_view bytes) {
  const int fd = open_new_file(file);
  try {
    write_all(fd, bytes, file);
  } catch (...) {
    ::close(fd);
    ::unlink(file.c_str());
    throw;
  }
  sync_and_close(fd, file);
}

// Makes a rename durable. Best effort: the file is complete and in place
// either way, and some file systems refuse to sync a folder.
void sync_directory_of(const fs::path& file) {
  const fs::path dir = file.has_parent_path() ? file.parent_path() : ".";
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

void rename_over(const fs::path& from, const fs::path& to) {
  if (std::rename(from.c_str(), to.c_str()) != 0) {
    const int err = errno;
    ::unlink(from.c_str());
    fail(to, "cannot rename " + from.string() + " over it", err);
  }
}

}  // namespace

FileWriteError::FileWriteError(const fs::path& path, const std::string& why)
    : std::runtime_error(path.string() + ": " + why), path_(path), why_(why) {}

void require_replaceable(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    throw FileWriteError(path, "exists and is not a regular file; not replaced");
}

void write_file_atomically(const fs::path& path, std::string_view bytes) {
  AtomicFileWriter out(path);
  out.write(bytes);
  out.commit();
}

AtomicFileWriter::AtomicFileWriter(fs::path path)
    : path_(std::move(path)), tmp_path_(path_.string() + ".tmp") {
  require_replaceable(path_);
  fd_ = open_new_file(tmp_path_);
}

AtomicFileWriter::~AtomicFileWriter() {
  if (committed_) return;
  if (fd_ >= 0) ::close(fd_);
  ::unlink(tmp_path_.c_str());
}

void AtomicFileWriter::write(std::string_view bytes) {
  if (fd_ < 0) throw FileWriteError(tmp_path_, "cannot write: already committed or failed");
  write_all(fd_, bytes, tmp_path_);
}

void AtomicFileWriter::commit() {
  if (fd_ < 0) throw FileWriteError(tmp_path_, "cannot commit: already committed or failed");
  const int fd = fd_;
  fd_ = -1;
  sync_and_close(fd, tmp_path_);  // removes the file on failure
  rename_over(tmp_path_, path_);  // likewise
  committed_ = true;
  sync_directory_of(path_);
}

void copy_file_atomically(const fs::path& from, const fs::path& to) {
  std::ifstream in(from, std::ios::binary);
  if (!in) fail(from, "cannot open", errno);
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) fail(from, "cannot read", errno);
  write_file_atomically(to, bytes);
}

StagedFiles::StagedFiles(std::vector<fs::path> targets, std::string suffix)
    : targets_(std::move(targets)), suffix_(std::move(suffix)) {
  for (const fs::path& t : targets_)
    require_replaceable(t);
  for (std::size_t i = 0; i < targets_.size(); ++i)
    pending_.push_back(std::make_unique<PendingFile>(staged(i)));
}

StagedFiles::~StagedFiles() {
  if (committed_) return;
  for (std::size_t i = 0; i < targets_.size(); ++i) {
    // Only a regular file of ours is removed, never something else of that name.
    const fs::path s = staged(i);
    struct stat st {};
    if (::lstat(s.c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::unlink(s.c_str());
  }
}

fs::path StagedFiles::staged(std::size_t i) const {
  return targets_.at(i).string() + suffix_;
}

void StagedFiles::write(std::size_t i, std::string_view bytes) {
  write_new_file(staged(i), bytes);
}

void StagedFiles::commit() {
  for (std::size_t i = 0; i < targets_.size(); ++i) {
    struct stat st {};
    if (::lstat(staged(i).c_str(), &st) != 0 || !S_ISREG(st.st_mode))
      throw FileWriteError(staged(i), "was not written");
  }
  for (std::size_t i = 0; i < targets_.size(); ++i)
    rename_over(staged(i), targets_[i]);
  committed_ = true;
  for (const fs::path& t : targets_)
    sync_directory_of(t);
}

void write_files_atomically(const std::vector<std::pair<fs::path, std::string>>& files) {
  std::vector<fs::path> targets;
  for (const auto& f : files)
    targets.push_back(f.first);
  StagedFiles staged(std::move(targets), ".tmp");
  for (std::size_t i = 0; i < files.size(); ++i)
    staged.write(i, files[i].second);
  staged.commit();
}

}  // namespace truecut::rt
