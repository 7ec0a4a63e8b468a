#include "mesh_io/ply_header.hpp"

#include "mesh_io/number_text.hpp"
#include "truecut/offline/mesh_io_error.hpp"

#include <array>
#include <optional>

namespace truecut::offline::mesh_io {

namespace {

struct TypeName {
  std::string_view name;
  PlyType type;
};
constexpr std::array<TypeName, 16> kTypeNames{{
    {"char", PlyType::kInt8},
    {"int8", PlyType::kInt8},
    {"uchar", PlyType::kUint8},
    {"uint8", PlyType::kUint8},
    {"short", PlyType::kInt16},
    {"int16", PlyType::kInt16},
    {"ushort", PlyType::kUint16},
    {"uint16", PlyType::kUint16},
    {"int", PlyType::kInt32},
    {"int32", PlyType::kInt32},
    {"uint", PlyType::kUint32},
    {"uint32", PlyType::kUint32},
    {"float", PlyType::kFloat32},
    {"float32", PlyType::kFloat32},
    {"double", PlyType::kFloat64},
    {"float64", PlyType::kFloat64},
}};

std::optional<PlyType> type_from_name(std::string_view name) {
  for (const TypeName& t : kTypeNames) {
    if (t.name == name) return t.type;
  }
  return std::nullopt;
}

}  // namespace

std::size_t ply_type_size(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

bool ply_type_is_integer(PlyType type) {
  return type != PlyType::kFloat32 && type != PlyType::kFloat64;
}

bool PlyElement::has_lists() const {
  for (const PlyProperty& p : properties) {
    if (p.is_list) return true;
  }
  return false;
}

std::size_t PlyElement::min_record_bytes() const {
  std::size_t n = 0;
  for (const PlyProperty& p : properties) {
    n += ply_type_size(p.is_list ? p.count_type : p.type);
  }
  return n;
}

int PlyElement::find(std::string_view name) const {
  for (std::size_t i = 0; i < properties.size(); ++i) {
    if (properties[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

PlyHeader read_ply_header(BufferedReader& in) {
  PlyHeader h;
  std::string_view line;
  std::vector<std::string_view> tok;
  bool have_format = false;
  auto fail = [&](const std::string& what) {
    throw MeshIoError(in.path(), "PLY header line " + std::to_string(h.lines) + ": " + what);
  };

  if (!in.next_line(line) || trim_blanks(line) != "ply") {
    throw MeshIoError(in.path(), "not a PLY file (the first line is not \"ply\")");
  }
  h.lines = 1;
  for (;;) {
    if (!in.next_line(line)) {
      throw MeshIoError(in.path(), "truncated PLY header: no \"end_header\" after " +
                                       std::to_string(h.lines) + " lines");
    }
    ++h.lines;
    split_blanks(line, tok);
    if (tok.empty()) continue;
    const std::string_view key = tok[0];
    if (key == "comment" || key == "obj_info") {
      std::string_view rest = trim_blanks(line.substr(tok[0].data() + tok[0].size() - line.data()));
      h.comments.emplace_back(key == "obj_info" ? "obj_info " + std::string(rest)
                                                : std::string(rest));
    } else if (key == "format") {
      if (tok.size() != 3) fail("expected \"format <encoding> 1.0\"");
      if (tok[1] == "ascii") {
        h.encoding = PlyEncoding::kAscii;
      } else if (tok[1] == "binary_little_endian") {
        h.encoding = PlyEncoding::kBinaryLittleEndian;
      } else if (tok[1] == "binary_big_endian") {
        h.encoding = PlyEncoding::kBinaryBigEndian;
      } else {
        fail("unknown encoding " + quote_token(tok[1]));
      }
      if (tok[2] != "1.0" && tok[2] != "1") fail("unsupported PLY version " + quote_token(tok[2]));
      have_format = true;
    } else if (key == "element") {
      std::int64_t count = 0;
      if (tok.size() != 3) fail("expected \"element <name> <count>\"");
      if (!parse_int(tok[2], count) || count < 0) fail("bad element count " + quote_token(tok[2]));
      h.elements.push_back({std::string(tok[1]), static_cast<std::uint64_t>(count), {}});
    } else if (key == "property") {
      if (h.elements.empty()) fail("property before any element");
      PlyProperty p;
      if (tok.size() >= 2 && tok[1] == "list") {
        if (tok.size() != 5) fail("expected \"property list <count type> <item type> <name>\"");
        auto count_type = type_from_name(tok[2]);
        auto item_type = type_from_name(tok[3]);
        if (!count_type) fail("unknown type " + quote_token(tok[2]));
        if (!item_type) fail("unknown type " + quote_token(tok[3]));
        if (!ply_type_is_integer(*count_type)) fail("a list count must have an integer type");
        p = {std::string(tok[4]), *item_type, true, *count_type};
      } else {
        if (tok.size() != 3) fail("expected \"property <type> <name>\"");
        auto type = type_from_name(tok[1]);
        if (!type) fail("unknown type " + quote_token(tok[1]));
        p = {std::string(tok[2]), *type, false, PlyType::kUint8};
      }
      h.elements.back().properties.push_back(std::move(p));
    } else if (key == "end_header") {
      break;
    } else {
      fail("unknown keyword " + quote_token(key));
    }
  }
  if (!have_format) throw MeshIoError(in.path(), "PLY header has no \"format\" line");
  return h;
}

double load_ply_double(const char* p, PlyType type, ByteOrder order) {
  switch (type) {
    case PlyType::kInt8:
      return load<std::int8_t>(p, order);
    case PlyType::kUint8:
      return load<std::uint8_t>(p, order);
    case PlyType::kInt16:
      return load<std::int16_t>(p, order);
    case PlyType::kUint16:
      return load<std::uint16_t>(p, order);
    case PlyType::kInt32:
      return load<std::int32_t>(p, order);
    case PlyType::kUint32:
      return load<std::uint32_t>(p, order);
    case PlyType::kFloat32:
      return load<float>(p, order);
    case PlyType::kFloat64:
      return load<double>(p, order);
  }
  return 0;
}

std::int64_t load_ply_integer(const char* p, PlyType type, ByteOrder order) {
  switch (type) {
    case PlyType::kInt8:
      return load<std::int8_t>(p, order);
    case PlyType::kUint8:
      return load<std::uint8_t>(p, order);
    case PlyType::kInt16:
      return load<std::int16_t>(p, order);
    case PlyType::kUint16:
      return load<std::uint16_t>(p, order);
    case PlyType::kInt32:
      return load<std::int32_t>(p, order);
    case PlyType::kUint32:
      return load<std::uint32_t>(p, order);
    default:
      return -1;  // callers only pass integer types
  }
}

}  // namespace truecut::offline::mesh_io
