// Reading a cmm.csv (write_cmm_csv) back: points, deviations, validity.
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "truecut/sim/measure/cmm.hpp"

namespace truecut::sim::measure {

std::vector<CmmMeasurement> read_cmm_measurements(const std::filesystem::path& file) {
  const std::vector<CmmPoint> points = read_cmm_points(file);
  std::ifstream in(file, std::ios::binary);
  std::string line;
  int dev_col = -1, valid_col = -1;
  std::size_t line_no = 0;
  std::vector<CmmMeasurement> out;
  out.reserve(points.size());
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string f; std::getline(ss, f, ',');)
      fields.push_back(f);
    if (dev_col < 0 && valid_col < 0 && out.empty()) {
      for (std::size_t i = 0; i < fields.size(); ++i) {
        if (fields[i] == "deviation_mm") dev_col = static_cast<int>(i);
        if (fields[i] == "valid") valid_col = static_cast<int>(i);
      }
      if (dev_col < 0 || valid_col < 0)
        throw CmmInputError(file.string() + ":" + std::to_string(line_no) +
                            ": header lacks deviation_mm or valid (a cmm.csv of truecut cmm)");
      continue;
    }
    const std::string where = file.string() + ":" + std::to_string(line_no) + ": ";
    if (out.size() >= points.size() ||
        static_cast<int>(fields.size()) <= std::max(dev_col, valid_col))
      throw CmmInputError(where + "expected the columns of the header");
    CmmMeasurement m;
    m.nominal = points[out.size()];
    m.valid = fields[valid_col] == "1";
    m.deviation_mm = m.valid ? std::strtod(fields[dev_col].c_str(), nullptr)
                             : std::numeric_limits<double>::quiet_NaN();
    if (m.valid && !std::isfinite(m.deviation_mm))
      throw CmmInputError(where + "valid point with deviation '" + fields[dev_col] + "'");
    m.measured_mm = m.nominal.position_mm + (m.valid ? m.deviation_mm : 0.0) * m.nominal.normal;
    out.push_back(m);
  }
  if (out.size() != points.size()) throw CmmInputError(file.string() + ": truncated");
  return out;
}

}  // namespace truecut::sim::measure
