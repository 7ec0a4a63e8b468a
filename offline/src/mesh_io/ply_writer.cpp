#include "mesh_io/byte_order.hpp"
#include "mesh_io/mesh_checks.hpp"
#include "mesh_io/number_text.hpp"
#include "mesh_io/output_file.hpp"
#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/offline/ply_io.hpp"

#include <limits>

namespace truecut::offline {

namespace {

using namespace mesh_io;

std::string one_line(std::string_view text) {
  std::string s(text);
  for (char& c : s) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return s;
}

std::string header(PlyEncoding encoding, std::size_t vertices, bool normals,
                   const std::vector<Triangle>* triangles, std::string_view comment) {
  std::string h = "ply\nformat ";
  h += encoding == PlyEncoding::kAscii             ? "ascii"
       : encoding == PlyEncoding::kBinaryBigEndian ? "binary_big_endian"
                                                   : "binary_little_endian";
  h += " 1.0\ncomment written by truecut; units mm\n";
  if (!comment.empty()) h += "comment " + one_line(comment) + "\n";
  h += "element vertex " + std::to_string(vertices) +
       "\nproperty double x\nproperty double y\nproperty double z\n";
  if (normals) h += "property double nx\nproperty double ny\nproperty double nz\n";
  if (triangles) {
    h += "element face " + std::to_string(triangles->size()) +
         "\nproperty list uchar uint vertex_indices\n";
  }
  return h + "end_header\n";
}

void write_binary(OutputFile& out, const std::vector<Eigen::Vector3d>& points,
                  const std::vector<Eigen::Vector3d>& normals,
                  const std::vector<Triangle>* triangles, ByteOrder order, std::string_view word) {
  const bool with_normals = !normals.empty();
  const std::size_t record = with_normals ? 48 : 24;
  std::vector<char> buf(record << 14);
  std::size_t used = 0;
  auto flush_if_full = [&](std::size_t next) {
    if (used + next > buf.size()) {
      out.write(buf.data(), used);
      used = 0;
    }
  };
  for (std::size_t i = 0; i < points.size(); ++i) {
    check_writable_vertex(points[i], i, out.path(), word);
    flush_if_full(record);
    char* r = buf.data() + used;
    for (int k = 0; k < 3; ++k) {
      store<double>(r + 8 * k, points[i][k], order);
    }
    if (with_normals) {
      check_writable_normal(normals[i], i, out.path());
      for (int k = 0; k < 3; ++k) {
        store<double>(r + 24 + 8 * k, normals[i][k], order);
      }
    }
    used += record;
  }
  if (triangles) {
    constexpr std::size_t kFace = 1 + 3 * 4;
    for (const Triangle& t : *triangles) {
      flush_if_full(kFace);
      char* r = buf.data() + used;
      r[0] = 3;
      for (int k = 0; k < 3; ++k) {
        store<std::uint32_t>(r + 1 + 4 * k, t[k], order);
      }
      used += kFace;
    }
  }
  out.write(buf.data(), used);
}

void write_ascii(OutputFile& out, const std::vector<Eigen::Vector3d>& points,
                 const std::vector<Eigen::Vector3d>& normals,
                 const std::vector<Triangle>* triangles, std::string_view word) {
  std::string s;
  for (std::size_t i = 0; i < points.size(); ++i) {
    check_writable_vertex(points[i], i, out.path(), word);
    for (int k = 0; k < 3; ++k) {
      if (k) s += ' ';
      append_double(s, points[i][k]);
    }
    if (!normals.empty()) {
      check_writable_normal(normals[i], i, out.path());
      for (int k = 0; k < 3; ++k) {
        s += ' ';
        append_double(s, normals[i][k]);
      }
    }
    s += '\n';
    out.write_if_large(s);
  }
  if (triangles) {
    for (const Triangle& t : *triangles) {
      s += '3';
      for (std::uint32_t v : t) {
        s += ' ';
        append_uint(s, v);
      }
      s += '\n';
      out.write_if_large(s);
    }
  }
  out.write(s);
}

void write(const std::filesystem::path& file, const std::vector<Eigen::Vector3d>& points,
           const std::vector<Eigen::Vector3d>& normals, const std::vector<Triangle>* triangles,
           PlyEncoding encoding, std::string_view comment, std::string_view word) {
  if (!normals.empty() && normals.size() != points.size()) {
    throw MeshIoError(file, std::to_string(normals.size()) + " normals for " +
                                std::to_string(points.size()) + " points");
  }
  OutputFile out(file);
  out.write(header(encoding, points.size(), !normals.empty(), triangles, comment));
  if (encoding == PlyEncoding::kAscii) {
    write_ascii(out, points, normals, triangles, word);
  } else {
    const ByteOrder order =
        encoding == PlyEncoding::kBinaryBigEndian ? ByteOrder::kBig : ByteOrder::kLittle;
    write_binary(out, points, normals, triangles, order, word);
  }
  out.commit();
}

}  // namespace

void write_ply(const std::filesystem::path& file, const TriangleMesh& mesh, PlyEncoding encoding,
               std::string_view comment) {
  check_writable(mesh, file);
  write(file, mesh.vertices_mm, mesh.normals, &mesh.triangles, encoding, comment, "vertex");
}

void write_ply(const std::filesystem::path& file, const PointCloud& cloud, PlyEncoding encoding,
               std::string_view comment) {
  write(file, cloud.points_mm, cloud.normals, nullptr, encoding, comment, "point");
}

}  // namespace truecut::offline
