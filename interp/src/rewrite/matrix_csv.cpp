// Reader of the compensation matrix CSV (docs/formats.md).
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numeric>
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

// No machine is larger than 100 m, and no compensation of a finished part
// is a metre: beyond these a value is a unit or writing mistake.
constexpr double kMaxPositionMm = 1e5;
constexpr double kMaxVectorMm = 1e3;

// One point at one position: a second one with another vector (or surface)
// would make the blend depend on which of the two the search meets first.
void refuse_repeated_points(const CompensationMatrixData& m, const std::vector<int>& lines,
                            const std::string& name) {
  std::vector<std::size_t> order(m.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto key = [&](std::size_t i) {
    const auto& p = m.positions_mm[i];
    return std::array<double, 3>{p.x(), p.y(), p.z()};
  };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return key(a) != key(b) ? key(a) < key(b) : a < b;
  });
  for (std::size_t k = 1; k < order.size(); ++k) {
    const std::size_t a = order[k - 1], b = order[k];
    if (key(a) != key(b)) continue;
    if (m.vectors_mm[a] == m.vectors_mm[b] && m.surface_ids[a] == m.surface_ids[b] &&
        m.valid[a] == m.valid[b])
      continue;
    fail(name, lines[b],
         "the point at x y z of line " + std::to_string(lines[a]) +
             " is given again with another vector, surface or validity: which one holds?");
  }
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
  std::vector<int> line_of_point;

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
      const double limit = c <= kZ ? kMaxPositionMm : c <= kDz ? kMaxVectorMm : INFINITY;
      if (std::abs(v[c]) > limit)
        fail(name, line_no,
             std::string(kNames[c]) + " " + std::string(cell) + " mm is outside ±" +
                 (c <= kZ ? "1e5 mm (no machine is larger than 100 m)"
                          : "1e3 mm (no compensation of a finished part is a metre)") +
                 "; check the unit");
    }
    if (v[kValid] != 0 && v[kValid] != 1) fail(name, line_no, "valid must be 0 or 1");
    if (v[kSurface] != std::floor(v[kSurface]) || std::fabs(v[kSurface]) > 2e9)
      fail(name, line_no, "surface_id must be an integer");
    m.positions_mm.emplace_back(v[kX], v[kY], v[kZ]);
    m.vectors_mm.emplace_back(v[kDx], v[kDy], v[kDz]);
    m.valid.push_back(static_cast<std::uint8_t>(v[kValid]));
    m.surface_ids.push_back(static_cast<std::int32_t>(v[kSurface]));
    line_of_point.push_back(line_no);
  }
  if (!have_header) fail(name, 0, "no header line x,y,z,dx,dy,dz (empty compensation matrix)");
  if (m.size() == 0) fail(name, 0, "no compensation points");
  refuse_repeated_points(m, line_of_point, name);
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
