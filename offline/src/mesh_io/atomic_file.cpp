#include "mesh_io/atomic_file.hpp"

#include "truecut/offline/mesh_io_error.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace truecut::offline::mesh_io {

namespace {
constexpr std::size_t kFlushBytes = 1 << 20;
}

AtomicFile::AtomicFile(const std::filesystem::path& file)
    : path_(file), tmp_path_(file.string() + ".tmp") {
  file_ = std::fopen(tmp_path_.c_str(), "wb");
  if (!file_) {
    throw MeshIoError(path_, "cannot create " + tmp_path_.string() + ": " + std::strerror(errno));
  }
  std::setvbuf(file_, nullptr, _IOFBF, kFlushBytes);
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  if (file_) std::fclose(file_);
  std::error_code ec;
  std::filesystem::remove(tmp_path_, ec);
}

void AtomicFile::fail(const std::string& what) {
  throw MeshIoError(path_, what + " " + tmp_path_.string() + ": " + std::strerror(errno));
}

void AtomicFile::write(const void* data, std::size_t size) {
  if (size > 0 && std::fwrite(data, 1, size, file_) != size) fail("cannot write");
}

void AtomicFile::write_if_large(std::string& pending) {
  if (pending.size() < kFlushBytes) return;
  write(pending);
  pending.clear();
}

void AtomicFile::commit() {
  if (std::fflush(file_) != 0) fail("cannot write");
  // Without the sync a crash after the rename could leave an empty FILE.
  if (::fsync(::fileno(file_)) != 0) fail("cannot sync");
  std::FILE* f = file_;
  file_ = nullptr;
  if (std::fclose(f) != 0) fail("cannot close");
  std::error_code ec;
  std::filesystem::rename(tmp_path_, path_, ec);
  if (ec) throw MeshIoError(path_, "cannot rename " + tmp_path_.string() + ": " + ec.message());
  committed_ = true;
  sync_directory();
}

// Makes the rename itself durable. Best effort: the file is complete and in
// place either way, and some file systems refuse to sync a directory.
void AtomicFile::sync_directory() const {
  const std::filesystem::path dir = path_.has_parent_path() ? path_.parent_path() : ".";
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace truecut::offline::mesh_io
