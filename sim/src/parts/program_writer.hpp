// Writes RS274/NGC text with fixed, locale-independent number formatting so
// that generated programs are byte-for-byte reproducible.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <string_view>

namespace truecut::sim::parts {

// "%.4f" without a negative zero.
std::string number(double v, int decimals = 4);

class ProgramWriter {
 public:
  void line(std::string_view text);
  void comment(std::string_view text);  // "(text)"
  void operation(std::string_view name);
  // "G0"/"G1" with X Y Z and optionally A C and F.
  void move(std::string_view g, const Eigen::Vector3d& p_mm, std::optional<double> f = {});
  void move5(std::string_view g, const Eigen::Vector3d& p_mm, double a_deg, double c_deg,
             std::optional<double> f = {});
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

}  // namespace truecut::sim::parts
