#include "output_spool.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace truecut::cli {

OutputSpool::OutputSpool(std::size_t memory_limit_bytes) : memory_limit_(memory_limit_bytes) {}

OutputSpool::~OutputSpool() {
  if (file_ != nullptr) std::fclose(file_);
}

void OutputSpool::spill() {
  if (file_ == nullptr) {
    file_ = std::tmpfile();  // removed by the system when closed, or when the process ends
    if (file_ == nullptr)
      throw std::runtime_error(std::string("cannot create a temporary file for the output: ") +
                               std::strerror(errno));
  }
  if (!buffer_.empty() && std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
    throw std::runtime_error(std::string("cannot write the output's temporary file: ") +
                             std::strerror(errno));
  buffer_.clear();
}

void OutputSpool::append(std::string_view text) {
  buffer_.append(text);
  size_ += text.size();
  if (buffer_.size() >= memory_limit_) spill();
}

void OutputSpool::write_to(std::FILE* out) {
  if (file_ != nullptr) {
    spill();
    std::rewind(file_);
    char chunk[1 << 16];
    std::size_t n;
    while ((n = std::fread(chunk, 1, sizeof chunk, file_)) > 0)
      std::fwrite(chunk, 1, n, out);
    if (std::ferror(file_))
      throw std::runtime_error(std::string("cannot read the output's temporary file back: ") +
                               std::strerror(errno));
    return;
  }
  std::fwrite(buffer_.data(), 1, buffer_.size(), out);
}

}  // namespace truecut::cli
