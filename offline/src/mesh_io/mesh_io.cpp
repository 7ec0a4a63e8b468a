#include "truecut/offline/mesh_io.hpp"

#include "mesh_io/buffered_reader.hpp"
#include "mesh_io/number_text.hpp"
#include "mesh_io/stl_detect.hpp"

#include <algorithm>
#include <cctype>

namespace truecut::offline {

namespace {

using namespace mesh_io;

bool is_point_text(std::string_view head) {
  // The first line that is neither blank nor a comment starts with a number
  // or a column name, and the bytes are text.
  if (!looks_like_text(head)) return false;
  while (!head.empty()) {
    const std::size_t nl = head.find('\n');
    std::string_view line = trim_blanks(head.substr(0, nl));
    if (!line.empty() && line[0] != '#') {
      const char c = line[0];
      return std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.' ||
             std::isalpha(static_cast<unsigned char>(c)) || c == '/' || c == '"';
    }
    if (nl == std::string_view::npos) break;
    head.remove_prefix(nl + 1);
  }
  return false;
}

bool is_ply(std::string_view head) {
  return head.starts_with("ply\n") || head.starts_with("ply\r\n") || head == "ply";
}

bool is_ascii_stl(std::string_view head) {
  return starts_with_solid(head) && looks_like_text(head) &&
         (head.find("facet") != std::string_view::npos ||
          head.find("endsolid") != std::string_view::npos);
}

}  // namespace

std::optional<MeshFormat> format_from_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  if (ext == ".stl") return MeshFormat::kStl;
  if (ext == ".ply") return MeshFormat::kPly;
  if (ext == ".xyz" || ext == ".txt" || ext == ".csv") return MeshFormat::kXyz;
  return std::nullopt;
}

MeshFormat detect_format(const std::filesystem::path& file) {
  BufferedReader in(file, kStlSniffBytes);
  if (in.file_size() == 0) throw MeshIoError(file, "empty file");
  const std::size_t n =
      static_cast<std::size_t>(std::min<std::uint64_t>(in.file_size(), kStlSniffBytes));
  const char* p = in.peek(n);
  if (!p) throw MeshIoError(file, "cannot read the first bytes");
  const std::string_view head(p, n);
  if (is_ply(head)) return MeshFormat::kPly;
  if (!looks_like_text(head) && binary_stl_size_matches(head, in.file_size())) {
    return MeshFormat::kStl;
  }
  if (is_ascii_stl(head)) return MeshFormat::kStl;
  if (auto by_extension = format_from_extension(file)) return *by_extension;
  if (is_point_text(head)) return MeshFormat::kXyz;
  throw MeshIoError(file, "unknown format: the extension " +
                              quote_token(file.extension().string()) +
                              " is not .stl, .ply, .xyz, .txt or .csv, and the content is "
                              "neither PLY, STL nor numeric text");
}

TriangleMesh read_mesh(const std::filesystem::path& file, const MeshReadOptions& options,
                       MeshReadReport* report) {
  switch (detect_format(file)) {
    case MeshFormat::kStl:
      return read_stl(file, options, report);
    case MeshFormat::kPly:
      return read_ply(file, options, report);
    case MeshFormat::kXyz:
      break;
  }
  PointCloud cloud = read_point_text(file, report);
  TriangleMesh mesh;
  mesh.vertices_mm = std::move(cloud.points_mm);
  mesh.normals = std::move(cloud.normals);
  return mesh;
}

PointCloud read_point_cloud(const std::filesystem::path& file, const MeshReadOptions& options,
                            MeshReadReport* report) {
  if (detect_format(file) == MeshFormat::kXyz) return read_point_text(file, report);
  TriangleMesh mesh = read_mesh(file, options, report);
  return {std::move(mesh.vertices_mm), std::move(mesh.normals)};
}

void write_mesh(const std::filesystem::path& file, const TriangleMesh& mesh,
                const MeshWriteOptions& options) {
  const auto format = format_from_extension(file);
  if (!format) {
    throw MeshIoError(file, "unknown output format: use .stl, .ply, .xyz, .txt or .csv");
  }
  switch (*format) {
    case MeshFormat::kStl:
      return write_stl(file, mesh, options.ascii ? StlEncoding::kAscii : StlEncoding::kBinary,
                       options.comment);
    case MeshFormat::kPly:
      return write_ply(file, mesh,
                       options.ascii ? PlyEncoding::kAscii : PlyEncoding::kBinaryLittleEndian,
                       options.comment);
    case MeshFormat::kXyz:
      break;
  }
  if (!mesh.triangles.empty()) {
    throw MeshIoError(file, "a point format cannot hold the mesh's " +
                                std::to_string(mesh.triangles.size()) +
                                " triangles; write .stl or .ply, or write the vertices with "
                                "write_point_cloud");
  }
  write_point_cloud(file, PointCloud{mesh.vertices_mm, mesh.normals}, options);
}

void write_point_cloud(const std::filesystem::path& file, const PointCloud& cloud,
                       const MeshWriteOptions& options) {
  const auto format = format_from_extension(file);
  if (format == MeshFormat::kPly) {
    return write_ply(file, cloud,
                     options.ascii ? PlyEncoding::kAscii : PlyEncoding::kBinaryLittleEndian,
                     options.comment);
  }
  if (format == MeshFormat::kXyz) {
    std::string ext = file.extension().string();
    for (char& c : ext) {
      c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    const bool csv = ext == ".csv";
    return write_point_text(file, cloud, {csv ? ',' : ' ', csv && options.csv_header});
  }
  throw MeshIoError(file, "cannot write a point cloud here: use .ply, .xyz, .txt or .csv");
}

}  // namespace truecut::offline
