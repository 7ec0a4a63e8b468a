// A mesh, point-cloud or matrix writer's output: rt::AtomicFileWriter (the
// project's one atomic file writer: FILE.tmp, synced, renamed over FILE on
// commit(), removed when destroyed without it), with its errors reported as
// MeshIoError("FILE: why") and a batching helper for text formatters.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/rt/atomic_write.hpp"

namespace truecut::offline::mesh_io {

class OutputFile {
 public:
  // Throws MeshIoError when FILE.tmp cannot be created (or FILE is not a
  // regular file).
  explicit OutputFile(const std::filesystem::path& file) : path_(file) {
    guarded([&] { out_.emplace(file); });
  }

  const std::filesystem::path& path() const { return path_; }
  void write(const void* data, std::size_t size) {
    write(std::string_view(static_cast<const char*>(data), size));
  }
  void write(std::string_view bytes) {
    guarded([&] { out_->write(bytes); });
  }
  // Writes `pending` and clears it once it has grown past kFlushBytes, so
  // formatters can append to one string without holding a whole file.
  void write_if_large(std::string& pending) {
    if (pending.size() < kFlushBytes) return;
    write(pending);
    pending.clear();
  }
  void commit() {
    guarded([&] { out_->commit(); });
  }

 private:
  static constexpr std::size_t kFlushBytes = 1 << 20;

  template <class F>
  void guarded(F&& f) {
    try {
      f();
    } catch (const rt::FileWriteError& e) {
      throw MeshIoError(path_, e.path() == path_ ? e.why() : e.path().string() + ": " + e.why());
    }
  }

  std::filesystem::path path_;
  std::optional<rt::AtomicFileWriter> out_;
};

}  // namespace truecut::offline::mesh_io
