// Output held back until a command has succeeded: text is gathered in memory
// and, beyond a threshold, in an anonymous temporary file, then copied out at
// the end. A command that fails prints nothing of it, and a long output costs
// no more memory than the threshold.
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>

namespace truecut::cli {

class OutputSpool {
 public:
  explicit OutputSpool(std::size_t memory_limit_bytes = std::size_t{32} << 20);
  ~OutputSpool();
  OutputSpool(const OutputSpool&) = delete;
  OutputSpool& operator=(const OutputSpool&) = delete;

  void append(std::string_view text);
  // Copies everything appended to `out`; throws std::runtime_error when the
  // temporary file cannot be written or read back.
  void write_to(std::FILE* out);
  std::size_t size() const { return size_; }
  bool spilled() const { return file_ != nullptr; }

 private:
  void spill();
  std::size_t memory_limit_;
  std::string buffer_;
  std::FILE* file_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace truecut::cli
