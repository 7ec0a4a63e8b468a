#include "mesh_io/buffered_reader.hpp"
#include "mesh_io/byte_order.hpp"
#include "mesh_io/mesh_checks.hpp"
#include "mesh_io/number_text.hpp"
#include "mesh_io/stl_detect.hpp"
#include "mesh_io/vertex_welder.hpp"
#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/offline/stl_io.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <string>

namespace truecut::offline {

namespace {

using mesh_io::BufferedReader;

std::string printable_header(std::string_view raw) {
  raw = raw.substr(0, raw.find('\0'));
  std::string s;
  for (char c : raw) {
    s += (static_cast<unsigned char>(c) < 0x20) ? ' ' : c;
  }
  return std::string(mesh_io::trim_blanks(s));
}

// Collects corners either welded or one vertex per corner.
template <class Scalar>
class CornerSink {
 public:
  CornerSink(bool weld, std::size_t corners) : weld_(weld), welder_(weld ? corners / 4 : 0) {
    if (!weld) plain_.reserve(corners);
  }
  std::uint32_t add(Scalar x, Scalar y, Scalar z) {
    if (weld_) return welder_.add(x, y, z);
    plain_.emplace_back(x, y, z);
    return static_cast<std::uint32_t>(plain_.size() - 1);
  }
  std::vector<Eigen::Vector3d> take_vertices() {
    return weld_ ? welder_.vertices() : std::move(plain_);
  }
  std::size_t merged() const { return weld_ ? welder_.merged() : 0; }

 private:
  bool weld_;
  mesh_io::VertexWelder<Scalar> welder_;
  std::vector<Eigen::Vector3d> plain_;
};

void check_corner_finite(double x, double y, double z, std::size_t facet, int corner,
                         const std::filesystem::path& file, const std::string& where = {}) {
  if (std::isfinite(x) && std::isfinite(y) && std::isfinite(z)) return;
  throw MeshIoError(file, "facet " + std::to_string(facet) + " corner " + std::to_string(corner) +
                              where + " has a non-finite coordinate " +
                              mesh_io::format_point({x, y, z}));
}

TriangleMesh read_binary(BufferedReader& in, const MeshReadOptions& options,
                         MeshReadReport& report) {
  using namespace mesh_io;
  const std::uint64_t size = in.file_size();
  const char* pre = in.peek(kStlPreambleBytes);
  if (!pre) {
    throw MeshIoError(in.path(), "truncated binary STL: expected at least " +
                                     std::to_string(kStlPreambleBytes) +
                                     " bytes (80-byte header and facet count), the file has " +
                                     std::to_string(size));
  }
  const std::string header = printable_header({pre, kStlHeaderBytes});
  if (!header.empty()) report.comments.push_back(header);
  const std::uint32_t facets = load<std::uint32_t>(pre + kStlHeaderBytes, ByteOrder::kLittle);
  const std::uint64_t expected = kStlPreambleBytes + std::uint64_t{kStlFacetBytes} * facets;
  if (size < expected) {
    throw MeshIoError(in.path(), "truncated binary STL: the header declares " +
                                     std::to_string(facets) + " facets, which need " +
                                     std::to_string(expected) + " bytes, but the file has " +
                                     std::to_string(size) + " bytes; it ends inside facet " +
                                     std::to_string((size - kStlPreambleBytes) / kStlFacetBytes));
  }
  if (size > expected) {
    throw MeshIoError(in.path(),
                      "binary STL facet count does not match the data: the header "
                      "declares " +
                          std::to_string(facets) + " facets (" + std::to_string(expected) +
                          " bytes), the file has " + std::to_string(size) + " bytes");
  }
  in.consume(kStlPreambleBytes);
  report.encoding = "binary";
  report.faces_in_file = facets;

  TriangleMesh mesh;
  mesh.triangles.resize(facets);
  CornerSink<float> corners(options.weld_stl_vertices, std::size_t{3} * facets);
  constexpr std::size_t kBatch = 1 << 14;
  for (std::size_t first = 0; first < facets;) {
    const std::size_t n = std::min<std::size_t>(kBatch, facets - first);
    const char* p = in.peek(n * kStlFacetBytes);
    if (!p) {
      throw MeshIoError(in.path(),
                        "the file shrank while being read, at facet " + std::to_string(first));
    }
    for (std::size_t f = first; f < first + n; ++f, p += kStlFacetBytes) {
      for (int c = 0; c < 3; ++c) {
        const char* v = p + 12 + 12 * c;
        float x = load<float>(v, ByteOrder::kLittle);
        float y = load<float>(v + 4, ByteOrder::kLittle);
        float z = load<float>(v + 8, ByteOrder::kLittle);
        check_corner_finite(x, y, z, f, c, in.path());
        mesh.triangles[f][c] = corners.add(x, y, z);
      }
    }
    in.consume(n * kStlFacetBytes);
    first += n;
  }
  mesh.vertices_mm = corners.take_vertices();
  report.stl_corners_welded = corners.merged();
  return mesh;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

TriangleMesh read_ascii(BufferedReader& in, const MeshReadOptions& options,
                        MeshReadReport& report) {
  using namespace mesh_io;
  enum class State { kOutside, kSolid, kFacet, kLoop, kLoopDone };
  report.encoding = "ascii";
  // A guess for the reservation: ~250 bytes of text per facet.
  CornerSink<double> corners(options.weld_stl_vertices,
                             static_cast<std::size_t>(std::min<std::uint64_t>(
                                 in.file_size() / 80, std::uint64_t{1} << 26)));
  TriangleMesh mesh;
  State state = State::kOutside;
  std::size_t line_no = 0, facet = 0, solids = 0;
  int corner = 0;
  Triangle tri{};
  std::string_view line;
  std::vector<std::string_view> tok;
  auto where = [&] {
    std::string s = "line " + std::to_string(line_no);
    if (state != State::kOutside && state != State::kSolid) {
      s += " (facet " + std::to_string(facet) + ")";
    }
    return s;
  };
  auto fail = [&](const std::string& what) { throw MeshIoError(in.path(), where() + ": " + what); };
  auto expect = [&](std::string_view wanted, const std::string& found) {
    fail("expected '" + std::string(wanted) + "', found " + quote_token(found));
  };

  while (in.next_line(line)) {
    ++line_no;
    split_blanks(line, tok);
    if (tok.empty()) continue;
    const std::string key = lower(tok[0]);
    switch (state) {
      case State::kOutside:
        if (key != "solid") expect("solid", std::string(tok[0]));
        if (tok.size() > 1) {
          report.comments.emplace_back(trim_blanks(line.substr(tok[1].data() - line.data())));
        }
        ++solids;
        state = State::kSolid;
        break;
      case State::kSolid:
        if (key == "endsolid") {
          state = State::kOutside;
        } else if (key == "facet") {
          state = State::kFacet;
          corner = 0;
        } else {
          fail("expected 'facet' or 'endsolid', found " + quote_token(tok[0]));
        }
        break;
      case State::kFacet:
        if (key != "outer" || tok.size() < 2 || lower(tok[1]) != "loop") {
          expect("outer loop", std::string(line));
        }
        state = State::kLoop;
        break;
      case State::kLoop:
        if (key == "vertex") {
          if (tok.size() != 4) fail("expected 'vertex x y z', found " + quote_token(line));
          double v[3];
          for (int k = 0; k < 3; ++k) {
            if (!parse_double(tok[k + 1], v[k])) fail(quote_token(tok[k + 1]) + " is not a number");
          }
          check_corner_finite(v[0], v[1], v[2], facet, corner, in.path(),
                              " (line " + std::to_string(line_no) + ")");
          if (corner >= 3) fail("facet " + std::to_string(facet) + " has more than 3 vertices");
          tri[corner++] = corners.add(v[0], v[1], v[2]);
        } else if (key == "endloop") {
          if (corner != 3) {
            fail("facet " + std::to_string(facet) + " has " + std::to_string(corner) +
                 " vertices, a triangle needs 3");
          }
          state = State::kLoopDone;
        } else {
          fail("expected 'vertex' or 'endloop', found " + quote_token(tok[0]));
        }
        break;
      case State::kLoopDone:
        if (key != "endfacet") expect("endfacet", std::string(tok[0]));
        mesh.triangles.push_back(tri);
        ++facet;
        state = State::kSolid;
        break;
    }
  }
  if (state == State::kSolid) {
    throw MeshIoError(in.path(), "truncated ASCII STL: the file ends after facet " +
                                     std::to_string(facet) + " (line " + std::to_string(line_no) +
                                     ") without 'endsolid'");
  }
  if (state != State::kOutside) {
    throw MeshIoError(in.path(), "truncated ASCII STL: the file ends inside facet " +
                                     std::to_string(facet) + " (line " + std::to_string(line_no) +
                                     ")");
  }
  if (solids == 0) throw MeshIoError(in.path(), "empty file: no 'solid' found");
  report.faces_in_file = mesh.triangles.size();
  mesh.vertices_mm = corners.take_vertices();
  report.stl_corners_welded = corners.merged();
  return mesh;
}

}  // namespace

TriangleMesh read_stl(const std::filesystem::path& file, const MeshReadOptions& options,
                      MeshReadReport* report) {
  using namespace mesh_io;
  BufferedReader in(file);
  if (in.file_size() == 0) throw MeshIoError(file, "empty file");
  const std::size_t sniff =
      static_cast<std::size_t>(std::min<std::uint64_t>(in.file_size(), kStlSniffBytes));
  const char* head = in.peek(sniff);
  if (!head) throw MeshIoError(file, "cannot read the first bytes");
  if (sniff == in.file_size() &&
      std::string_view(head, sniff).find_first_not_of(" \t\r\n") == std::string_view::npos)
    throw MeshIoError(file, "empty file (only blanks)");
  const bool ascii = stl_is_ascii({head, sniff}, in.file_size());

  MeshReadReport local;
  MeshReadReport& rep = report ? *report : local;
  rep = MeshReadReport{};
  rep.format = MeshFormat::kStl;
  // Text that is not a binary STL of the right size but does not start with
  // 'solid' (a typo, another format): read as binary, its first bytes would
  // give a nonsense facet count.
  const std::string_view sniffed(head, sniff);
  if (!ascii && looks_like_text(sniffed) && !binary_stl_size_matches(sniffed, in.file_size())) {
    const std::size_t end = std::min(sniffed.find_first_of("\r\n"), std::size_t{40});
    const std::string first(sniffed.substr(0, end));
    if (sniffed.find("facet") != std::string_view::npos ||
        sniffed.find("vertex") != std::string_view::npos)
      throw MeshIoError(file,
                        "looks like an ASCII STL (text with 'facet' and 'vertex') but does "
                        "not start with 'solid': its first line is '" +
                            first + "'");
    throw MeshIoError(file,
                      "is text, not an STL: an ASCII STL starts with 'solid', this file "
                      "with '" +
                          first + "'");
  }
  TriangleMesh mesh = ascii ? read_ascii(in, options, rep) : read_binary(in, options, rep);
  std::vector<std::uint32_t> identity;
  handle_degenerate_triangles(mesh.triangles, identity, mesh.vertices_mm, options, file, "facet",
                              rep);
  return mesh;
}

}  // namespace truecut::offline
