#include "parts/program_writer.hpp"

#include "truecut/rt/number_format.hpp"

namespace truecut::sim::parts {

std::string number(double v, int decimals) {
  return rt::format_fixed(v, decimals);
}

void ProgramWriter::line(std::string_view text) {
  text_ += text;
  text_ += '\n';
}

void ProgramWriter::comment(std::string_view text) {
  text_ += '(';
  text_ += text;
  text_ += ")\n";
}

void ProgramWriter::operation(std::string_view name) {
  text_ += "(OPERATION: ";
  text_ += name;
  text_ += ")\n";
}

void ProgramWriter::move(std::string_view g, const Eigen::Vector3d& p_mm, std::optional<double> f) {
  std::string s(g);
  s += " X" + number(p_mm.x()) + " Y" + number(p_mm.y()) + " Z" + number(p_mm.z());
  if (f) s += " F" + number(*f, 0);
  line(s);
}

void ProgramWriter::move5(std::string_view g, const Eigen::Vector3d& p_mm, double a_deg,
                          double c_deg, std::optional<double> f) {
  std::string s(g);
  s += " X" + number(p_mm.x()) + " Y" + number(p_mm.y()) + " Z" + number(p_mm.z());
  s += " A" + number(a_deg, 3) + " C" + number(c_deg, 3);
  if (f) s += " F" + number(*f, 0);
  line(s);
}

}  // namespace truecut::sim::parts
