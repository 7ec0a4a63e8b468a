// Reads a text file line by line in fixed-size chunks, accepting CR, LF and
// CRLF line endings (a CR-only file is one "line" to std::getline).
#pragma once

#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace truecut::analysis::detail {

class LineReader {
 public:
  explicit LineReader(const std::filesystem::path& file);  // throws RecordingError
  ~LineReader();
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  // The next line without its ending; false at end of file.
  bool next(std::string& line);
  // 1-based number of the line last returned.
  std::size_t line_number() const { return line_number_; }

 private:
  bool fill();

  std::FILE* in_ = nullptr;
  std::string file_;
  std::vector<char> buf_;
  std::size_t pos_ = 0, end_ = 0;
  bool eof_ = false;
  bool skip_lf_ = false;  // the previous line ended in CR; a following LF belongs to it
  std::size_t line_number_ = 0;
};

// Splits one CSV line at `delimiter` (',' ';' or '\t'); double-quoted fields
// may hold delimiters and "" for a quote. Leading and trailing blanks of
// unquoted fields are dropped.
void split_csv(const std::string& line, std::vector<std::string>& fields, char delimiter = ',');

// The delimiter of a header line: the most frequent of ',', ';' and tab
// outside quotes (',' when none occurs).
char detect_delimiter(const std::string& header);

}  // namespace truecut::analysis::detail
