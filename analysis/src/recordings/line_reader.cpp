#include "line_reader.hpp"

#include <cerrno>
#include <cstring>

#include "truecut/analysis/recording.hpp"
#include "truecut/rt/input_file.hpp"

namespace truecut::analysis::detail {

LineReader::LineReader(const std::filesystem::path& file) : file_(file.string()), buf_(1 << 16) {
  try {
    rt::check_input_file(file, "recording");
  } catch (const rt::InputFileError& e) {
    throw RecordingError(e.what());
  }
  in_ = std::fopen(file_.c_str(), "rb");
  if (!in_) throw RecordingError(file_ + ": cannot open: " + std::strerror(errno));
}

LineReader::~LineReader() {
  if (in_) std::fclose(in_);
}

bool LineReader::fill() {
  if (eof_) return false;
  end_ = std::fread(buf_.data(), 1, buf_.size(), in_);
  pos_ = 0;
  if (end_ == 0) {
    if (std::ferror(in_)) throw RecordingError(file_ + ": read error");
    eof_ = true;
    return false;
  }
  return true;
}

bool LineReader::next(std::string& line) {
  line.clear();
  bool any = false;
  for (;;) {
    if (pos_ == end_ && !fill()) {
      if (!any) return false;
      ++line_number_;
      return true;
    }
    if (skip_lf_) {
      skip_lf_ = false;
      if (buf_[pos_] == '\n') {
        ++pos_;
        continue;
      }
    }
    const char* begin = buf_.data() + pos_;
    const char* stop = begin;
    const char* limit = buf_.data() + end_;
    while (stop != limit && *stop != '\n' && *stop != '\r')
      ++stop;
    line.append(begin, stop);
    any = true;
    pos_ += static_cast<std::size_t>(stop - begin);
    if (stop != limit) {
      skip_lf_ = *stop == '\r';
      ++pos_;
      ++line_number_;
      return true;
    }
  }
}

char detect_delimiter(const std::string& header) {
  std::size_t comma = 0, semicolon = 0, tab = 0;
  bool quoted = false;
  for (char c : header) {
    if (c == '"') quoted = !quoted;
    if (quoted) continue;
    comma += c == ',', semicolon += c == ';', tab += c == '\t';
  }
  if (semicolon > comma && semicolon >= tab) return ';';
  if (tab > comma && tab > semicolon) return '\t';
  return ',';
}

void split_csv(const std::string& line, std::vector<std::string>& fields, char delimiter) {
  std::size_t n = 0;
  auto next_field = [&]() -> std::string& {
    if (n == fields.size()) fields.emplace_back();
    fields[n].clear();
    return fields[n++];
  };
  std::size_t i = 0;
  const std::size_t size = line.size();
  for (;;) {
    std::string& f = next_field();
    while (i < size && (line[i] == ' ' || (line[i] == '\t' && delimiter != '\t')))
      ++i;
    if (i < size && line[i] == '"') {
      ++i;
      while (i < size) {
        if (line[i] == '"') {
          if (i + 1 < size && line[i + 1] == '"') {
            f += '"';
            i += 2;
            continue;
          }
          ++i;
          break;
        }
        f += line[i++];
      }
      while (i < size && line[i] != delimiter)
        ++i;
    } else {
      const std::size_t start = i;
      while (i < size && line[i] != delimiter)
        ++i;
      std::size_t stop = i;
      while (stop > start &&
             (line[stop - 1] == ' ' || (line[stop - 1] == '\t' && delimiter != '\t')))
        --stop;
      f.assign(line, start, stop - start);
    }
    if (i >= size) break;
    ++i;  // the delimiter
  }
  fields.resize(n);
}

}  // namespace truecut::analysis::detail
