// Reading CMM point lists and writing cmm.csv (docs/measurement.md, "Files").
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <system_error>
#include <vector>

#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/input_file.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/measure/cmm.hpp"

namespace truecut::sim::measure {
namespace {

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::string current;
  for (char ch : line) {
    if (ch == '#') break;
    if (ch == ',' || ch == ';' || std::isspace(static_cast<unsigned char>(ch))) {
      if (!current.empty()) fields.push_back(std::move(current));
      current.clear();
    } else {
      current += ch;
    }
  }
  if (!current.empty()) fields.push_back(std::move(current));
  return fields;
}

bool parse_number(const std::string& text, double& value) {
  const char* begin = text.c_str();
  char* end = nullptr;
  value = std::strtod(begin, &end);
  return end != begin && *end == '\0';
}

// "x 1e+20 mm is outside ±1e+05 mm (...)", or "" for a coordinate a machine can reach.
std::string implausible_coordinate(const char* axis, double value_mm) {
  if (std::abs(value_mm) <= kMaxCmmCoordinateMm) return "";
  return std::string(axis) + " " + rt::format_shortest(value_mm) + " mm is outside ±" +
         rt::format_shortest(kMaxCmmCoordinateMm) +
         " mm (no machine is larger than 100 m; check the unit)";
}

void append_number(std::string& out, double value) {
  char buf[32];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, value);
  out.append(buf, ec == std::errc() ? ptr : buf);
}

}  // namespace

std::string cmm_coordinate_error(const Eigen::Vector3d& position_mm) {
  for (int k = 0; k < 3; ++k)
    if (std::string bad = implausible_coordinate(k == 0   ? "x"
                                                 : k == 1 ? "y"
                                                          : "z",
                                                 position_mm[k]);
        !bad.empty())
      return bad;
  return "";
}

std::vector<CmmPoint> read_cmm_points(const std::filesystem::path& file) {
  try {
    rt::check_input_file(file, "CMM point list");
  } catch (const rt::InputFileError& e) {
    throw CmmInputError(e.what());
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw CmmInputError(file.string() + ": cannot open");
  const std::string name = file.string();
  // Column of x y z nx ny nz surface (−1: absent).
  std::vector<int> column{0, 1, 2, 3, 4, 5, -1};
  bool first_content = true, named = false;
  std::vector<CmmPoint> points;
  std::string line;
  for (std::size_t line_no = 1; std::getline(in, line); ++line_no) {
    const std::vector<std::string> fields = split_fields(line);
    if (fields.empty()) continue;
    const std::string where = name + ":" + std::to_string(line_no) + ": ";
    double probe_value = 0;
    if (first_content && !parse_number(fields[0], probe_value)) {
      first_content = false;
      named = true;
      std::map<std::string, int> index;
      for (std::size_t i = 0; i < fields.size(); ++i) {
        std::string key = fields[i];
        std::transform(key.begin(), key.end(), key.begin(),
                       [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
        index.emplace(key, static_cast<int>(i));
      }
      const char* keys[] = {"x", "y", "z", "nx", "ny", "nz", "surface"};
      for (std::size_t k = 0; k < 7; ++k) {
        const auto it = index.find(keys[k]);
        if (it != index.end()) {
          column[k] = it->second;
        } else if (k < 6) {
          throw CmmInputError(where + "header lacks the column '" + keys[k] +
                              "' (needs x y z nx ny nz [surface])");
        } else {
          column[k] = -1;
        }
      }
      continue;
    }
    first_content = false;
    if (!named) {
      if (fields.size() != 6 && fields.size() != 7)
        throw CmmInputError(where + "expected 6 or 7 values (x y z nx ny nz [surface]), found " +
                            std::to_string(fields.size()));
      column[6] = fields.size() == 7 ? 6 : -1;
    }
    double v[7] = {0, 0, 0, 0, 0, 0, -1};
    for (std::size_t k = 0; k < 7; ++k) {
      if (column[k] < 0) continue;
      const auto c = static_cast<std::size_t>(column[k]);
      if (c >= fields.size())
        throw CmmInputError(where + "missing value in column " + std::to_string(c + 1));
      if (!parse_number(fields[c], v[k]) || !std::isfinite(v[k]))
        throw CmmInputError(where + "'" + fields[c] + "' is not a finite number");
    }
    CmmPoint p;
    p.position_mm = {v[0], v[1], v[2]};
    if (const std::string bad = cmm_coordinate_error(p.position_mm); !bad.empty())
      throw CmmInputError(where + bad);
    p.normal = {v[3], v[4], v[5]};
    if (!(p.normal.norm() > 1e-12)) throw CmmInputError(where + "zero normal");
    p.normal.normalize();
    if (v[6] != std::floor(v[6]) || std::abs(v[6]) > 2e9)
      throw CmmInputError(where + "surface id '" + fields[static_cast<std::size_t>(column[6])] +
                          "' is not an integer");
    p.surface = static_cast<int>(v[6]);
    points.push_back(p);
  }
  if (in.bad()) throw CmmInputError(name + ": read error");
  if (points.empty()) throw CmmInputError(name + ": no points");
  return points;
}

void write_cmm_csv(const std::filesystem::path& file,
                   std::span<const CmmMeasurement> measurements) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw CmmInputError(file.string() + ": exists and is not a regular file; not replaced");
  std::string text = "x,y,z,nx,ny,nz,surface,deviation_mm,valid\n";
  for (const CmmMeasurement& m : measurements) {
    for (int k = 0; k < 3; ++k) {
      append_number(text, m.nominal.position_mm[k]);
      text += ',';
    }
    for (int k = 0; k < 3; ++k) {
      append_number(text, m.nominal.normal[k]);
      text += ',';
    }
    text += std::to_string(m.nominal.surface);
    text += ',';
    if (m.valid)
      append_number(text, m.deviation_mm);
    else
      text += "nan";
    text += m.valid ? ",1\n" : ",0\n";
  }
  rt::write_file_atomically(file, text);
}

}  // namespace truecut::sim::measure
