#include "mesh_io/buffered_reader.hpp"
#include "mesh_io/mesh_checks.hpp"
#include "mesh_io/number_text.hpp"
#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/offline/point_text_io.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <optional>

namespace truecut::offline {

namespace {

using namespace mesh_io;

bool is_separator(char c) {
  return c == ',' || c == ';';
}

// Hand-written loops: string_view::find_first_of costs several times more
// per character, which showed on million-point files.
void split_fields(std::string_view line, std::vector<std::string_view>& out) {
  if (std::none_of(line.begin(), line.end(), is_separator)) return split_blanks(line, out);
  out.clear();
  std::size_t start = 0;
  for (std::size_t i = 0; i <= line.size(); ++i) {
    if (i == line.size() || is_separator(line[i])) {
      out.push_back(trim_blanks(line.substr(start, i - start)));
      start = i + 1;
    }
  }
}

std::string column_name(std::string_view field) {
  std::string s;
  for (char c : field) {
    if (c != '"' && c != '\'') s += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return s;
}

// Columns of x y z nx ny nz, or nullopt when the header names no x, y, z.
std::optional<std::array<int, 6>> columns_by_name(const std::vector<std::string_view>& names,
                                                  bool& normals) {
  static constexpr std::array<std::array<std::string_view, 2>, 6> kNames{{{"x", "x"},
                                                                          {"y", "y"},
                                                                          {"z", "z"},
                                                                          {"nx", "normal_x"},
                                                                          {"ny", "normal_y"},
                                                                          {"nz", "normal_z"}}};
  std::array<int, 6> col{-1, -1, -1, -1, -1, -1};
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string n = column_name(names[i]);
    for (int s = 0; s < 6; ++s) {
      if (col[s] < 0 && (n == kNames[s][0] || n == kNames[s][1])) col[s] = static_cast<int>(i);
    }
  }
  if (col[0] < 0 || col[1] < 0 || col[2] < 0) return std::nullopt;
  normals = col[3] >= 0 && col[4] >= 0 && col[5] >= 0;
  return col;
}

}  // namespace

PointCloud read_point_text(const std::filesystem::path& file, MeshReadReport* report) {
  BufferedReader in(file);
  if (in.file_size() == 0) throw MeshIoError(file, "empty file");
  MeshReadReport local;
  MeshReadReport& rep = report ? *report : local;
  rep = MeshReadReport{};
  rep.format = MeshFormat::kXyz;
  rep.encoding = "ascii";

  PointCloud cloud;
  cloud.points_mm.reserve(
      static_cast<std::size_t>(std::min<std::uint64_t>(in.file_size() / 24, 1u << 26)));
  std::array<int, 6> col{};
  std::size_t columns = 0;  // values per line, fixed by the header or the first data line
  bool normals = false, header = false;
  std::size_t line_no = 0;
  std::string_view line;
  std::vector<std::string_view> fields;
  auto fail = [&](const std::string& what) {
    throw MeshIoError(file, "line " + std::to_string(line_no) + ": " + what);
  };

  while (in.next_line(line)) {
    ++line_no;
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) {
      if (trim_blanks(line.substr(0, hash)).empty()) {
        rep.comments.emplace_back(trim_blanks(line.substr(hash + 1)));
      }
      line = line.substr(0, hash);
    }
    line = trim_blanks(line);
    if (line.empty()) continue;
    double value = 0;
    if (columns == 0 && !header) {
      if (line.starts_with("//")) {  // CloudCompare's header
        line = trim_blanks(line.substr(2));
        if (line.empty()) continue;  // "//" alone names no column
      }
      split_fields(line, fields);
      const char first = fields[0].empty() ? '\0' : fields[0][0];
      const bool names = std::isalpha(static_cast<unsigned char>(first)) || first == '"' ||
                         first == '\'' || first == '_';
      if (names && !parse_double(fields[0], value)) {
        header = true;
        columns = fields.size();
        if (auto named = columns_by_name(fields, normals)) {
          col = *named;
        } else if (columns == 3 || columns == 6) {
          col = {0, 1, 2, 3, 4, 5};
          normals = columns == 6;
        } else {
          fail("the header " + quote_token(line) + " names no x, y, z columns");
        }
        continue;
      }
      columns = fields.size();
      if (columns != 3 && columns != 6) {
        fail(std::to_string(columns) + " values; expected 3 (x y z) or 6 (x y z nx ny nz)");
      }
      col = {0, 1, 2, 3, 4, 5};
      normals = columns == 6;
    } else {
      split_fields(line, fields);
    }
    if (fields.size() != columns) {
      fail(std::to_string(fields.size()) + " values, but " +
           (header ? "the header names " : "the first data line has ") + std::to_string(columns) +
           " columns");
    }
    double v[6] = {};
    for (int s = 0; s < (normals ? 6 : 3); ++s) {
      if (!parse_double(fields[col[s]], v[s])) {
        fail("column " + std::to_string(col[s] + 1) + ": " + quote_token(fields[col[s]]) +
             " is not a number");
      }
    }
    const Eigen::Vector3d p(v[0], v[1], v[2]);
    const Eigen::Vector3d n(v[3], v[4], v[5]);
    if (!all_finite(p)) {
      fail("point " + std::to_string(cloud.points_mm.size()) + " has a non-finite coordinate " +
           format_point(p));
    }
    if (normals && !all_finite(n)) {
      fail("point " + std::to_string(cloud.points_mm.size()) + " has a non-finite normal " +
           format_point(n));
    }
    cloud.points_mm.push_back(p);
    if (normals) cloud.normals.push_back(n);
  }
  if (cloud.points_mm.empty() && !header) {
    throw MeshIoError(file, "empty file: no points (only comments or blank lines)");
  }
  return cloud;
}

}  // namespace truecut::offline
