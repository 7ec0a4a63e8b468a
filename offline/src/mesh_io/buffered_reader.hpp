// Reads a file through one growing buffer: binary data is handed out as
// pointers into the buffer (bulk, no per-value stream calls) and text as
// lines (string_views into the buffer), so large scans never sit in memory
// whole.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string_view>
#include <vector>

namespace truecut::offline::mesh_io {

class BufferedReader {
 public:
  // Throws MeshIoError when the file cannot be opened.
  explicit BufferedReader(const std::filesystem::path& file, std::size_t capacity = 1 << 20);
  ~BufferedReader();
  BufferedReader(const BufferedReader&) = delete;
  BufferedReader& operator=(const BufferedReader&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::uint64_t file_size() const { return file_size_; }
  // Bytes handed out (consumed) so far.
  std::uint64_t offset() const { return consumed_; }
  std::uint64_t remaining() const { return file_size_ - consumed_; }

  // At least n contiguous bytes starting at offset(), or nullptr when the file
  // ends first. The pointer stays valid until the next peek or next_line.
  const char* peek(std::size_t n);
  void consume(std::size_t n);

  // The next line without its "\n" or "\r\n"; false at end of file. The view
  // stays valid until the next peek or next_line.
  bool next_line(std::string_view& line);

 private:
  // Reads more of the file behind the unconsumed bytes; false at end of file.
  bool refill(std::size_t wanted);

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::uint64_t file_size_ = 0;
  std::uint64_t consumed_ = 0;
  std::vector<char> buffer_;
  std::size_t begin_ = 0;  // first unconsumed byte in buffer_
  std::size_t end_ = 0;    // one past the last valid byte in buffer_
  bool eof_ = false;
};

}  // namespace truecut::offline::mesh_io
