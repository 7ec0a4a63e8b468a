#include "mesh_io/buffered_reader.hpp"

#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/rt/input_file.hpp"

#include <cerrno>
#include <cstring>
#include <string>

namespace truecut::offline::mesh_io {

namespace {

// What is not a regular file goes through the check every reader shares: a
// FIFO would block the open, a device never ends. A regular file's size is
// left to the readers (scans may exceed the general input budget; they check
// the counts of their headers against the bytes that follow).
void check_regular_file(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(file, ec) && !ec) return;
  try {
    rt::check_input_file(file, "mesh or point cloud");
  } catch (const rt::InputFileError& e) {
    throw MeshIoError(file, e.reason());
  }
}

}  // namespace

BufferedReader::BufferedReader(const std::filesystem::path& file, std::size_t capacity)
    : path_(file), buffer_(capacity) {
  check_regular_file(file);
  std::error_code ec;
  file_ = std::fopen(file.c_str(), "rb");
  if (!file_) throw MeshIoError(file, std::string("cannot open: ") + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IONBF, 0);  // this class is the buffer
  file_size_ = std::filesystem::file_size(file, ec);
  if (ec) {
    std::fclose(file_);
    throw MeshIoError(file, "cannot read the file size: " + ec.message());
  }
}

BufferedReader::~BufferedReader() {
  if (file_) std::fclose(file_);
}

bool BufferedReader::refill(std::size_t wanted) {
  if (eof_) return false;
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  if (buffer_.size() < wanted) buffer_.resize(std::max(wanted, 2 * buffer_.size()));
  if (end_ == buffer_.size()) buffer_.resize(2 * buffer_.size());
  std::size_t got = std::fread(buffer_.data() + end_, 1, buffer_.size() - end_, file_);
  if (got == 0) {
    if (std::ferror(file_)) {
      throw MeshIoError(path_, std::string("read error: ") + std::strerror(errno));
    }
    eof_ = true;
    return false;
  }
  end_ += got;
  return true;
}

const char* BufferedReader::peek(std::size_t n) {
  while (end_ - begin_ < n) {
    if (!refill(n)) return nullptr;
  }
  return buffer_.data() + begin_;
}

void BufferedReader::consume(std::size_t n) {
  begin_ += n;
  consumed_ += n;
}

bool BufferedReader::next_line(std::string_view& line) {
  std::size_t searched = 0;  // bytes after begin_ known to hold no '\n'
  for (;;) {
    const char* start = buffer_.data() + begin_;
    std::size_t avail = end_ - begin_;
    const void* nl = std::memchr(start + searched, '\n', avail - searched);
    if (nl) {
      std::size_t len = static_cast<const char*>(nl) - start;
      consume(len + 1);
      if (len > 0 && start[len - 1] == '\r') --len;
      line = std::string_view(start, len);
      return true;
    }
    searched = avail;
    if (!refill(avail + 1)) {
      if (avail == 0) return false;
      start = buffer_.data() + begin_;  // the last line has no '\n'
      consume(avail);
      if (start[avail - 1] == '\r') --avail;
      line = std::string_view(start, avail);
      return true;
    }
  }
}

}  // namespace truecut::offline::mesh_io
