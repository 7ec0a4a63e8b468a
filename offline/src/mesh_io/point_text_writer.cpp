#include "mesh_io/mesh_checks.hpp"
#include "mesh_io/number_text.hpp"
#include "mesh_io/output_file.hpp"
#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/offline/point_text_io.hpp"

namespace truecut::offline {

void write_point_text(const std::filesystem::path& file, const PointCloud& cloud,
                      const PointTextFormat& format) {
  using namespace mesh_io;
  const char sep = format.separator;
  if (sep != ' ' && sep != '\t' && sep != ',' && sep != ';') {
    throw MeshIoError(file, "unsupported separator " + quote_token(std::string_view(&sep, 1)));
  }
  const bool normals = cloud.has_normals();
  if (normals && cloud.normals.size() != cloud.points_mm.size()) {
    throw MeshIoError(file, std::to_string(cloud.normals.size()) + " normals for " +
                                std::to_string(cloud.points_mm.size()) + " points");
  }
  OutputFile out(file);
  std::string s;
  if (format.header) {
    for (const char* name : {"x", "y", "z", "nx", "ny", "nz"}) {
      if (!normals && name[0] == 'n') break;
      if (!s.empty()) s += sep;
      s += name;
    }
    s += '\n';
  }
  for (std::size_t i = 0; i < cloud.points_mm.size(); ++i) {
    check_writable_vertex(cloud.points_mm[i], i, file, "point");
    for (int k = 0; k < 3; ++k) {
      if (k) s += sep;
      append_double(s, cloud.points_mm[i][k]);
    }
    if (normals) {
      check_writable_normal(cloud.normals[i], i, file);
      for (int k = 0; k < 3; ++k) {
        s += sep;
        append_double(s, cloud.normals[i][k]);
      }
    }
    s += '\n';
    out.write_if_large(s);
  }
  out.write(s);
  out.commit();
}

}  // namespace truecut::offline
