#include "mesh_io/buffered_reader.hpp"
#include "mesh_io/mesh_checks.hpp"
#include "mesh_io/number_text.hpp"
#include "mesh_io/ply_header.hpp"
#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/offline/ply_io.hpp"

#include <array>
#include <limits>
#include <span>

namespace truecut::offline {

namespace {

using namespace mesh_io;

enum class Role { kVertex, kFace, kSkip };
constexpr int kSlots = 6;  // x y z nx ny nz
constexpr std::size_t kBatchBytes = 1 << 20;

class PlyReader {
 public:
  PlyReader(const std::filesystem::path& file, const MeshReadOptions& options,
            MeshReadReport& report)
      : in_(file), options_(options), report_(report) {}

  TriangleMesh read();

 private:
  void plan();
  void check_sizes() const;
  void read_binary(const PlyElement& e, Role role);
  void read_binary_fixed(const PlyElement& e, Role role);
  void read_ascii(const PlyElement& e, Role role);
  void vertex_done(std::size_t k, const double* v);
  void face_done(std::size_t k, std::span<const std::int64_t> corners);
  const char* need(std::size_t bytes, const PlyElement& e, std::size_t k);
  std::string where(const PlyElement& e, std::size_t k) const;
  [[noreturn]] void fail(const std::string& what) const { throw MeshIoError(in_.path(), what); }

  BufferedReader in_;
  const MeshReadOptions& options_;
  MeshReadReport& report_;
  PlyHeader h_;
  ByteOrder order_ = ByteOrder::kLittle;
  bool ascii_ = false;
  std::size_t line_ = 0;  // ASCII: line number of the current record

  TriangleMesh mesh_;
  std::vector<std::uint32_t> source_face_;
  const PlyElement* vertex_element_ = nullptr;
  const PlyElement* face_element_ = nullptr;
  std::vector<int> vertex_slot_;  // per vertex property: slot or -1
  std::vector<int> face_slot_;    // per face property: 0 for the index list, else -1
  bool normals_ = false;
  std::vector<std::int64_t> corners_;
};

TriangleMesh PlyReader::read() {
  if (in_.file_size() == 0) fail("empty file");
  h_ = read_ply_header(in_);
  ascii_ = h_.encoding == PlyEncoding::kAscii;
  order_ = h_.encoding == PlyEncoding::kBinaryBigEndian ? ByteOrder::kBig : ByteOrder::kLittle;
  line_ = h_.lines;
  report_.format = MeshFormat::kPly;
  report_.encoding = ascii_                      ? "ascii"
                     : order_ == ByteOrder::kBig ? "binary_big_endian"
                                                 : "binary_little_endian";
  report_.comments = h_.comments;
  plan();
  check_sizes();

  mesh_.vertices_mm.resize(vertex_element_->count);
  if (normals_) mesh_.normals.resize(vertex_element_->count);
  if (face_element_) {
    mesh_.triangles.reserve(face_element_->count);
    source_face_.reserve(face_element_->count);
    report_.faces_in_file = face_element_->count;
  }
  for (const PlyElement& e : h_.elements) {
    const Role role = &e == vertex_element_ ? Role::kVertex
                      : &e == face_element_ ? Role::kFace
                                            : Role::kSkip;
    if (ascii_) {
      read_ascii(e, role);
    } else {
      read_binary(e, role);
    }
  }

  if (ascii_) {
    std::string_view line;
    std::vector<std::string_view> tok;
    while (in_.next_line(line)) {
      ++line_;
      split_blanks(line, tok);
      if (!tok.empty()) {
        fail("line " + std::to_string(line_) +
             ": data after the last element the header declares; the header's counts do not "
             "match the data");
      }
    }
  } else if (in_.remaining() > 0) {
    fail(std::to_string(in_.remaining()) + " bytes after the last element (file size " +
         std::to_string(in_.file_size()) + " bytes, elements end at byte " +
         std::to_string(in_.offset()) + "); the header's counts do not match the data");
  }

  check_finite(mesh_.vertices_mm, mesh_.normals, in_.path(), "vertex");
  handle_degenerate_triangles(mesh_.triangles, source_face_, mesh_.vertices_mm, options_,
                              in_.path(), "face", report_);
  return std::move(mesh_);
}

void PlyReader::plan() {
  for (const PlyElement& e : h_.elements) {
    if (e.name == "vertex") {
      if (vertex_element_) fail("more than one \"vertex\" element");
      vertex_element_ = &e;
    } else if (e.name == "face") {
      if (face_element_) fail("more than one \"face\" element");
      face_element_ = &e;
    }
  }
  if (!vertex_element_) fail("the PLY header declares no \"vertex\" element");
  const PlyElement& v = *vertex_element_;
  if (v.count > std::numeric_limits<std::uint32_t>::max()) {
    fail("too many vertices (" + std::to_string(v.count) + ") for 32-bit indices");
  }
  vertex_slot_.assign(v.properties.size(), -1);
  static constexpr std::array<std::string_view, kSlots> kNames{"x", "y", "z", "nx", "ny", "nz"};
  int normal_props = 0;
  for (int s = 0; s < kSlots; ++s) {
    const int i = v.find(kNames[s]);
    if (i < 0) {
      if (s < 3) fail("the vertex element has no \"" + std::string(kNames[s]) + "\" property");
      continue;
    }
    if (v.properties[i].is_list) {
      if (s < 3) fail("the vertex property \"" + std::string(kNames[s]) + "\" is a list");
      continue;
    }
    vertex_slot_[i] = s;
    if (s >= 3) ++normal_props;
  }
  normals_ = normal_props == 3;
  if (!normals_) {
    for (int& s : vertex_slot_) {
      if (s >= 3) s = -1;
    }
  }

  if (face_element_) {
    const PlyElement& f = *face_element_;
    if (f.count > std::numeric_limits<std::uint32_t>::max()) fail("too many faces");
    int i = f.find("vertex_indices");
    if (i < 0) i = f.find("vertex_index");
    if (i < 0) fail("the face element has no \"vertex_indices\" (or \"vertex_index\") property");
    if (!f.properties[i].is_list) {
      fail("the face property \"" + f.properties[i].name + "\" is not a list");
    }
    if (!ply_type_is_integer(f.properties[i].type)) {
      fail("the face property \"" + f.properties[i].name + "\" has a non-integer index type");
    }
    face_slot_.assign(f.properties.size(), -1);
    face_slot_[i] = 0;
  }
}

// Checks the declared counts against the bytes that follow the header before
// anything is allocated from them.
void PlyReader::check_sizes() const {
  const std::uint64_t size = in_.file_size();
  std::uint64_t at = in_.offset();
  for (const PlyElement& e : h_.elements) {
    std::uint64_t rec = e.min_record_bytes();
    // ASCII: only an allocation guard (a record takes at least one byte); the
    // record-by-record reading names the line where the counts go wrong.
    if (ascii_) rec = e.properties.empty() ? 0 : 1;
    const bool overflow =
        rec > 0 && e.count > (std::numeric_limits<std::uint64_t>::max() / 2) / rec;
    const std::uint64_t need =
        overflow ? std::numeric_limits<std::uint64_t>::max() / 2 : e.count * rec;
    const std::uint64_t left = size - std::min(size, at);
    if (need > left) {
      std::string msg = "truncated: the header declares " + std::to_string(e.count) + " \"" +
                        e.name + "\" records of ";
      if (ascii_) {
        msg += "at least one byte each, but only " + std::to_string(left) + " bytes follow";
      } else if (e.has_lists()) {
        msg += "at least " + std::to_string(rec) + " bytes each, which need at least " +
               std::to_string(need) + " bytes from byte " + std::to_string(at) +
               ", but the file has " + std::to_string(size) + " bytes";
      } else {
        msg += std::to_string(rec) + " bytes, which need " + std::to_string(need) +
               " bytes from byte " + std::to_string(at) + " (file size " +
               std::to_string(at + need) + "), but the file has " + std::to_string(size) +
               " bytes; it ends inside " + e.name + " " + std::to_string(left / rec);
      }
      fail(msg);
    }
    at += need;
  }
}

std::string PlyReader::where(const PlyElement& e, std::size_t k) const {
  std::string s = e.name + " " + std::to_string(k);
  if (ascii_) s += " (line " + std::to_string(line_) + ")";
  return s;
}

const char* PlyReader::need(std::size_t bytes, const PlyElement& e, std::size_t k) {
  // Checked first so that a corrupt list length cannot ask for a huge buffer.
  const char* p = bytes <= in_.remaining() ? in_.peek(bytes) : nullptr;
  if (!p) {
    fail("truncated: the file ends inside " + e.name + " " + std::to_string(k) + " of " +
         std::to_string(e.count) + ", which needs " + std::to_string(bytes) +
         " more bytes at byte " + std::to_string(in_.offset()) + ", but the file has " +
         std::to_string(in_.file_size()) + " bytes");
  }
  return p;
}

void PlyReader::read_binary(const PlyElement& e, Role role) {
  if (!e.has_lists()) return read_binary_fixed(e, role);
  double v[kSlots] = {};
  for (std::size_t k = 0; k < e.count; ++k) {
    corners_.clear();
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      if (!p.is_list) {
        const std::size_t size = ply_type_size(p.type);
        const char* b = need(size, e, k);
        if (role == Role::kVertex && vertex_slot_[i] >= 0) {
          v[vertex_slot_[i]] = load_ply_double(b, p.type, order_);
        }
        in_.consume(size);
        continue;
      }
      const std::size_t count_size = ply_type_size(p.count_type);
      const std::int64_t n = load_ply_integer(need(count_size, e, k), p.count_type, order_);
      if (n < 0) fail(where(e, k) + ": negative list length " + std::to_string(n));
      in_.consume(count_size);
      const std::size_t item = ply_type_size(p.type);
      const std::size_t bytes = static_cast<std::size_t>(n) * item;
      const char* b = need(bytes, e, k);
      if (role == Role::kFace && face_slot_[i] == 0) {
        corners_.resize(static_cast<std::size_t>(n));
        for (std::int64_t j = 0; j < n; ++j) {
          corners_[j] = load_ply_integer(b + j * item, p.type, order_);
        }
      }
      in_.consume(bytes);
    }
    if (role == Role::kVertex) vertex_done(k, v);
    if (role == Role::kFace) face_done(k, corners_);
  }
}

void PlyReader::read_binary_fixed(const PlyElement& e, Role role) {
  struct Field {
    std::size_t offset;
    PlyType type;
    int slot;
  };
  std::vector<Field> fields;
  std::size_t record = 0;
  for (std::size_t i = 0; i < e.properties.size(); ++i) {
    if (role == Role::kVertex && vertex_slot_[i] >= 0) {
      fields.push_back({record, e.properties[i].type, vertex_slot_[i]});
    }
    record += ply_type_size(e.properties[i].type);
  }
  if (record == 0) return;
  const std::size_t batch = std::max<std::size_t>(1, kBatchBytes / record);
  double v[kSlots] = {};
  for (std::size_t first = 0; first < e.count;) {
    const std::size_t n = std::min<std::uint64_t>(batch, e.count - first);
    const char* b = need(n * record, e, first);
    if (role == Role::kVertex) {
      for (std::size_t r = 0; r < n; ++r, b += record) {
        for (const Field& f : fields) {
          v[f.slot] = load_ply_double(b + f.offset, f.type, order_);
        }
        vertex_done(first + r, v);
      }
    }
    in_.consume(n * record);
    first += n;
  }
}

void PlyReader::read_ascii(const PlyElement& e, Role role) {
  if (e.properties.empty()) return;  // its records would be blank lines
  std::string_view line;
  std::vector<std::string_view> tok;
  double v[kSlots] = {};
  for (std::size_t k = 0; k < e.count; ++k) {
    do {
      if (!in_.next_line(line)) {
        fail("the file ends at " + e.name + " " + std::to_string(k) + " of " +
             std::to_string(e.count) + " declared (after line " + std::to_string(line_) +
             "); the header's counts do not match the data");
      }
      ++line_;
      split_blanks(line, tok);
    } while (tok.empty());
    std::size_t t = 0;
    auto next = [&]() -> std::string_view {
      if (t >= tok.size()) {
        fail(where(e, k) + ": fewer values than the header declares (" +
             std::to_string(tok.size()) + ")");
      }
      return tok[t++];
    };
    corners_.clear();
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      if (!p.is_list) {
        std::string_view s = next();
        if (role == Role::kVertex && vertex_slot_[i] >= 0 && !parse_double(s, v[vertex_slot_[i]])) {
          fail(where(e, k) + ": " + quote_token(s) + " is not a number");
        }
        continue;
      }
      std::int64_t n = 0;
      std::string_view s = next();
      if (!parse_int(s, n) || n < 0) fail(where(e, k) + ": bad list length " + quote_token(s));
      const bool keep = role == Role::kFace && face_slot_[i] == 0;
      for (std::int64_t j = 0; j < n; ++j) {
        std::string_view item = next();
        std::int64_t index = 0;
        if (keep) {
          if (!parse_int(item, index)) {
            fail(where(e, k) + ": " + quote_token(item) + " is not an integer");
          }
          corners_.push_back(index);
        }
      }
    }
    if (t != tok.size()) {
      fail(where(e, k) + ": " + std::to_string(tok.size()) +
           " values, more than the header declares");
    }
    if (role == Role::kVertex) vertex_done(k, v);
    if (role == Role::kFace) face_done(k, corners_);
  }
}

void PlyReader::vertex_done(std::size_t k, const double* v) {
  mesh_.vertices_mm[k] = Eigen::Vector3d(v[0], v[1], v[2]);
  if (normals_) mesh_.normals[k] = Eigen::Vector3d(v[3], v[4], v[5]);
}

void PlyReader::face_done(std::size_t k, std::span<const std::int64_t> corners) {
  const PlyElement& e = *face_element_;
  if (corners.size() < 3) {
    fail(where(e, k) + " has " + std::to_string(corners.size()) +
         " vertex indices; a face needs at least 3");
  }
  const std::uint64_t n = vertex_element_->count;
  for (std::int64_t c : corners) {
    if (c < 0 || static_cast<std::uint64_t>(c) >= n) {
      fail(where(e, k) + " refers to vertex " + std::to_string(c) + ", but the file has " +
           std::to_string(n) + " vertices");
    }
  }
  if (corners.size() > 3) ++report_.polygons_triangulated;
  // Fan from the first corner: exact for the convex polygons scanners write.
  for (std::size_t j = 1; j + 1 < corners.size(); ++j) {
    mesh_.triangles.push_back({static_cast<std::uint32_t>(corners[0]),
                               static_cast<std::uint32_t>(corners[j]),
                               static_cast<std::uint32_t>(corners[j + 1])});
    source_face_.push_back(static_cast<std::uint32_t>(k));
  }
}

}  // namespace

TriangleMesh read_ply(const std::filesystem::path& file, const MeshReadOptions& options,
                      MeshReadReport* report) {
  MeshReadReport local;
  MeshReadReport& rep = report ? *report : local;
  rep = MeshReadReport{};
  return PlyReader(file, options, rep).read();
}

}  // namespace truecut::offline
