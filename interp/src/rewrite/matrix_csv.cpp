// Reader of the compensation matrix CSV (docs/formats.md).
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "truecut/interp/rewrite_matrix.hpp"
#include "truecut/rt/input_file.hpp"

namespace truecut::interp {

namespace {

[[noreturn]] void fail(const std::string& name, int line, const std::string& what) {
  throw RewriteError(name + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + what);
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t'))
    s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace

CompensationMatrixData parse_compensation_matrix(std::string_view text, const std::string& name,
                                                 MatrixVectors vectors) {
  enum Column { kX, kY, kZ, kDx, kDy, kDz, kValid, kSurface, kCount };
  const bool raw = vectors == MatrixVectors::kRaw;
  const char* const kNames[kCount] = {"x",
                                      "y",
                                      "z",
                                      raw ? "raw_dx" : "dx",
                                      raw ? "raw_dy" : "dy",
                                      raw ? "raw_dz" : "dz",
                                      "valid",
                                      "surface_id"};
  int index[kCount];
  for (int& i : index)
    i = -1;
  size_t fields = 0;
  bool have_header = false;
  CompensationMatrixData m;

  int line_no = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = text.find_first_of("\r\n", pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = trim(text.substr(pos, end - pos));
    ++line_no;
    pos = end;
    if (pos < text.size() && text[pos] == '\r') ++pos;
    if (pos < text.size() && text[pos] == '\n') ++pos;
    if (line.empty() || line.front() == '#') continue;
    const auto cells = split(line);
    if (!have_header) {
      for (size_t k = 0; k < cells.size(); ++k)
        for (int c = 0; c < kCount; ++c)
          if (cells[k] == kNames[c]) {
            if (index[c] >= 0) fail(name, line_no, "column '" + std::string(kNames[c]) + "' twice");
            index[c] = static_cast<int>(k);
          }
      for (int c = kX; c <= kDz; ++c)
        if (index[c] < 0)
          fail(name, line_no,
               "header has no column '" + std::string(kNames[c]) +
                   (raw ? "' (--raw-matrix reads raw_dx,raw_dy,raw_dz, which truecut field "
                          "writes beside the smoothed dx,dy,dz)"
                        : "' (expected x,y,z,dx,dy,dz[,valid][,surface_id])"));
      fields = cells.size();
      have_header = true;
      continue;
    }
    if (cells.size() != fields)
      fail(name, line_no,
           std::to_string(cells.size()) + " fields, the header has " + std::to_string(fields));
    double v[kCount] = {0, 0, 0, 0, 0, 0, 1, 0};
    for (int c = 0; c < kCount; ++c) {
      if (index[c] < 0) continue;
      const std::string_view cell = cells[index[c]];
      const char* b = cell.data();
      const char* e = b + cell.size();
      if (!cell.empty() && *b == '+') ++b;
      const auto r = std::from_chars(b, e, v[c]);
      if (cell.empty() || r.ec != std::errc() || r.ptr != e)
        fail(name, line_no,
             std::string(kNames[c]) + " '" + std::string(cell) + "' is not a number");
      if (!std::isfinite(v[c]))
        fail(name, line_no, std::string(kNames[c]) + " is not finite (" + std::string(cell) + ")");
    }
    if (v[kValid] != 0 && v[kValid] != 1) fail(name, line_no, "valid must be 0 or 1");
    if (v[kSurface] != std::floor(v[kSurface]) || std::fabs(v[kSurface]) > 2e9)
      fail(name, line_no, "surface_id must be an integer");
    m.positions_mm.emplace_back(v[kX], v[kY], v[kZ]);
    m.vectors_mm.emplace_back(v[kDx], v[kDy], v[kDz]);
    m.valid.push_back(static_cast<std::uint8_t>(v[kValid]));
    m.surface_ids.push_back(static_cast<std::int32_t>(v[kSurface]));
  }
  if (!have_header) fail(name, 0, "no header line x,y,z,dx,dy,dz (empty compensation matrix)");
  if (m.size() == 0) fail(name, 0, "no compensation points");
  return m;
}

CompensationMatrixData read_compensation_matrix(const std::filesystem::path& file,
                                                MatrixVectors vectors) {
  std::string text;
  try {
    text = rt::read_input_file(file, "compensation matrix");
  } catch (const rt::InputFileError& e) {
    fail(file.string(), 0, e.reason());
  }
  return parse_compensation_matrix(text, file.string(), vectors);
}

}  // namespace truecut::interp
