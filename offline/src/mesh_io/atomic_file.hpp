// Output that appears under its final name only when complete: bytes go to
// FILE.tmp in the same folder, commit() flushes, syncs and renames it over
// FILE (then syncs the folder), and destruction without commit() removes
// FILE.tmp. A failing writer
// therefore never leaves a partial file, nor touches an existing FILE.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace truecut::offline::mesh_io {

class AtomicFile {
 public:
  // Throws MeshIoError when FILE.tmp cannot be created.
  explicit AtomicFile(const std::filesystem::path& file);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  void write(const void* data, std::size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }
  // Writes `pending` and clears it once it has grown past a flush threshold,
  // so formatters can append to one string without holding a whole file.
  void write_if_large(std::string& pending);
  void commit();

 private:
  [[noreturn]] void fail(const std::string& what);
  void sync_directory() const;

  std::filesystem::path path_;
  std::filesystem::path tmp_path_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

}  // namespace truecut::offline::mesh_io
