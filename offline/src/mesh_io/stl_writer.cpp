#include "mesh_io/byte_order.hpp"
#include "mesh_io/mesh_checks.hpp"
#include "mesh_io/number_text.hpp"
#include "mesh_io/output_file.hpp"
#include "mesh_io/stl_detect.hpp"
#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/offline/stl_io.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <cstring>
#include <limits>

namespace truecut::offline {

namespace {

using mesh_io::OutputFile;

Eigen::Vector3d facet_normal(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c) {
  Eigen::Vector3d n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

// Checks each corner as it is written: an invalid mesh stops the writer midway
// and OutputFile removes the partial FILE.tmp.
const Eigen::Vector3d& checked_corner(const TriangleMesh& mesh, std::uint32_t v,
                                      const std::filesystem::path& file, bool float32) {
  const Eigen::Vector3d& p = mesh.vertices_mm[v];
  mesh_io::check_writable_vertex(p, v, file, "vertex");
  if (float32 && p.cwiseAbs().maxCoeff() > std::numeric_limits<float>::max()) {
    throw MeshIoError(file, "cannot write vertex " + std::to_string(v) + " " +
                                mesh_io::format_point(p) + ": outside the float32 range of STL");
  }
  return p;
}

void write_binary(OutputFile& out, const TriangleMesh& mesh, std::string_view header) {
  using namespace mesh_io;
  char pre[kStlPreambleBytes] = {};
  std::string h = header.empty() ? std::string("truecut binary STL, mm") : std::string(header);
  std::memcpy(pre, h.data(), std::min(h.size(), kStlHeaderBytes));
  store<std::uint32_t>(pre + kStlHeaderBytes, static_cast<std::uint32_t>(mesh.triangles.size()),
                       ByteOrder::kLittle);
  out.write(pre, sizeof pre);

  constexpr std::size_t kBatch = 1 << 14;
  std::vector<char> buf(kBatch * kStlFacetBytes);
  std::size_t used = 0;
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3d* p[3];
    for (int c = 0; c < 3; ++c) {
      p[c] = &checked_corner(mesh, t[c], out.path(), true);
    }
    char* f = buf.data() + used;
    const Eigen::Vector3d n = facet_normal(*p[0], *p[1], *p[2]);
    for (int k = 0; k < 3; ++k) {
      store<float>(f + 4 * k, static_cast<float>(n[k]), ByteOrder::kLittle);
    }
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) {
        store<float>(f + 12 + 12 * c + 4 * k, static_cast<float>((*p[c])[k]), ByteOrder::kLittle);
      }
    }
    store<std::uint16_t>(f + 48, 0, ByteOrder::kLittle);
    used += kStlFacetBytes;
    if (used == buf.size()) {
      out.write(buf.data(), used);
      used = 0;
    }
  }
  out.write(buf.data(), used);
}

void append_xyz(std::string& s, const Eigen::Vector3d& p) {
  for (int k = 0; k < 3; ++k) {
    s += ' ';
    mesh_io::append_double(s, p[k]);
  }
}

void write_ascii(OutputFile& out, const TriangleMesh& mesh, std::string_view header) {
  std::string name = header.empty() ? std::string("truecut") : std::string(header);
  for (char& c : name) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  std::string s = "solid " + name + "\n";
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3d* p[3];
    for (int c = 0; c < 3; ++c) {
      p[c] = &checked_corner(mesh, t[c], out.path(), false);
    }
    s += "facet normal";
    append_xyz(s, facet_normal(*p[0], *p[1], *p[2]));
    s += "\n  outer loop\n";
    for (int c = 0; c < 3; ++c) {
      s += "    vertex";
      append_xyz(s, *p[c]);
      s += '\n';
    }
    s += "  endloop\nendfacet\n";
    out.write_if_large(s);
  }
  s += "endsolid " + name + "\n";
  out.write(s);
}

}  // namespace

void write_stl(const std::filesystem::path& file, const TriangleMesh& mesh, StlEncoding encoding,
               std::string_view header) {
  if (encoding == StlEncoding::kBinary && mesh_io::starts_with_solid(header)) {
    throw MeshIoError(file,
                      "a binary STL header must not start with \"solid\" (other readers "
                      "would take the file for ASCII)");
  }
  if (mesh.triangles.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw MeshIoError(file, "too many triangles for STL");
  }
  mesh_io::check_writable(mesh, file);
  OutputFile out(file);
  if (encoding == StlEncoding::kBinary) {
    write_binary(out, mesh, header);
  } else {
    write_ascii(out, mesh, header);
  }
  out.commit();
}

}  // namespace truecut::offline
