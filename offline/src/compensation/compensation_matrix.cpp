#include "truecut/offline/compensation_matrix.hpp"

#include "mesh_io/number_text.hpp"
#include "mesh_io/output_file.hpp"
#include "truecut/offline/mesh_io_error.hpp"

#include <cmath>
#include <stdexcept>
#include <string_view>

namespace truecut::offline {

CompensationMatrix mirror(const CompensationPoints& points, const ErrorVectors& errors) {
  const std::size_t n = points.size();
  if (errors.size() != n || errors.status.size() != n || points.surface_ids.size() != n) {
    throw std::invalid_argument(std::to_string(errors.size()) + " error vectors for " +
                                std::to_string(n) + " compensation points");
  }
  CompensationMatrix m;
  m.positions_mm = points.positions_mm;
  m.surface_ids = points.surface_ids;
  m.vectors_mm.resize(n);
  m.valid.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    m.valid[i] = errors.valid(i) ? 1 : 0;
    m.vectors_mm[i] =
        errors.valid(i) ? Eigen::Vector3d(-errors.vectors_mm[i]) : Eigen::Vector3d::Zero();
  }
  return m;
}

void write_compensation_matrix(const std::filesystem::path& file, const CompensationMatrix& m,
                               const std::string& comment) {
  using namespace mesh_io;
  const std::size_t n = m.size();
  const bool raw = !m.raw_vectors_mm.empty();
  if (m.vectors_mm.size() != n || m.valid.size() != n || m.surface_ids.size() != n ||
      (raw && m.raw_vectors_mm.size() != n)) {
    throw MeshIoError(file, "compensation matrix columns differ in length");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!m.positions_mm[i].allFinite() || !m.vectors_mm[i].allFinite() ||
        (raw && !m.raw_vectors_mm[i].allFinite())) {
      throw MeshIoError(file, "row " + std::to_string(i) + " has a non-finite value");
    }
  }
  OutputFile out(file);
  std::string s =
      "# truecut compensation matrix v1\n"
      "# frame: workpiece\n"
      "# units: mm\n";
  s +=
      raw ? "# dx,dy,dz: compensation vector, smoothed and significance-tested; 0 where valid = 0\n"
            "# raw_dx,raw_dy,raw_dz: -(measured - nominal), point by point, noise included\n"
          : "# dx,dy,dz: compensation vector = -(measured - nominal); 0 where valid = 0\n";
  std::string_view rest = comment;
  while (!rest.empty()) {
    const std::size_t eol = rest.find('\n');
    s += "# ";
    s += rest.substr(0, eol);
    s += '\n';
    rest = eol == std::string_view::npos ? std::string_view{} : rest.substr(eol + 1);
  }
  s += raw ? "x,y,z,dx,dy,dz,valid,surface_id,raw_dx,raw_dy,raw_dz\n"
           : "x,y,z,dx,dy,dz,valid,surface_id\n";
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      append_double(s, m.positions_mm[i][k] + 0.0);  // + 0.0: no "-0"
      s += ',';
    }
    for (int k = 0; k < 3; ++k) {
      append_double(s, m.vectors_mm[i][k] + 0.0);
      s += ',';
    }
    s += m.valid[i] ? '1' : '0';
    s += ',';
    s += std::to_string(m.surface_ids[i]);
    if (raw)
      for (int k = 0; k < 3; ++k) {
        s += ',';
        append_double(s, m.raw_vectors_mm[i][k] + 0.0);
      }
    s += '\n';
    out.write_if_large(s);
  }
  out.write(s);
  out.commit();
}

}  // namespace truecut::offline
