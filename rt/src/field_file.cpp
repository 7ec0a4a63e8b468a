// The `.tcf` correction-field file: text header, little-endian float64
// payload, CRC-64/XZ over both. Format: docs/formats.md.
#include "truecut/rt/field_file.hpp"

#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/input_file.hpp"
#include "truecut/rt/number_format.hpp"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

namespace truecut::rt {
namespace {

constexpr std::string_view kMagic = "TRUECUT-FIELD";
constexpr int kVersion = 1;
constexpr std::string_view kEndHeader = "end_header";
// The two channel layouts: the translation alone, or with the tool's
// rotation (rx ry rz, rad) before the weight.
constexpr std::string_view kChannels = "dx dy dz weight";
constexpr std::string_view kChannelsWithRotation = "dx dy dz rx ry rz weight";
constexpr std::string_view kEncoding = "float64-le";
constexpr std::size_t kMaxHeaderBytes = 64 * 1024;
constexpr const char* kChannelNames[] = {"dx", "dy", "dz", "weight"};
constexpr const char* kChannelNamesWithRotation[] = {"dx", "dy", "dz", "rx", "ry", "rz", "weight"};

int channel_count(bool rotation) {
  return rotation ? 7 : 4;
}
std::size_t bytes_per_node(bool rotation) {
  return static_cast<std::size_t>(channel_count(rotation)) * sizeof(double);
}
constexpr std::string_view kKeys[] = {
    "frame",    "units",   "origin", "spacing", "dims", "tools",    "interpolation", "channels",
    "encoding", "created", "source", "machine", "part", "tool_set", "payload_bytes", "crc64"};

// ---------------------------------------------------------------- helpers

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

std::vector<std::string_view> split_words(std::string_view s) {
  std::vector<std::string_view> words;
  std::size_t pos = 0;
  while (true) {
    pos = s.find_first_not_of(" \t", pos);
    if (pos == std::string_view::npos) return words;
    const std::size_t end = std::min(s.find_first_of(" \t", pos), s.size());
    words.push_back(s.substr(pos, end - pos));
    pos = end;
  }
}

template <typename T>
std::optional<T> parse_number(std::string_view word, int base = 10) {
  T value{};
  std::from_chars_result r;
  if constexpr (std::is_floating_point_v<T>)
    r = std::from_chars(word.data(), word.data() + word.size(), value);
  else
    r = std::from_chars(word.data(), word.data() + word.size(), value, base);
  if (r.ec != std::errc() || r.ptr != word.data() + word.size()) return std::nullopt;
  return value;
}

// A short, printable rendering of untrusted text for error messages.
std::string printable(std::string_view s) {
  std::string out = "'";
  for (const char ch : s.substr(0, 60))
    out += (ch >= 0x20 && ch < 0x7F) ? ch : '?';
  return out + (s.size() > 60 ? "...'" : "'");
}

// Writes v's 8 bytes little-endian at p and moves p past them.
void put_le(char*& p, double v) {
  uint64_t bits = std::bit_cast<uint64_t>(v);
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(p, &bits, sizeof bits);
  } else {
    for (int b = 0; b < 8; ++b, bits >>= 8)
      p[b] = static_cast<char>(bits & 0xFF);
  }
  p += sizeof bits;
}

double get_le(const char* p) {
  uint64_t bits = 0;
  for (int b = 7; b >= 0; --b)
    bits = (bits << 8) | static_cast<unsigned char>(p[b]);
  return std::bit_cast<double>(bits);
}

// ----------------------------------------------------------------- header

struct Header {
  std::map<std::string, std::string, std::less<>> values;
  std::map<std::string, std::size_t, std::less<>> lines;  // 1-based line of each key
  std::size_t crc_line_offset = 0;                        // the checksum covers the bytes before it
  std::size_t payload_offset = 0;
};

class Decoder {
 public:
  Decoder(std::string_view bytes, std::string_view name) : bytes_(bytes), name_(name) {}

  // The header alone (the payload need not be there): grid, tools, channels,
  // each in the range of a real machine, and the memory loading would take.
  FieldFileHeader header_only() {
    header_ = parse_header();
    FieldFileHeader h;
    h.grid.origin_mm = vector3(header_, "origin");
    h.grid.spacing_mm = vector3(header_, "spacing");
    check_origin(h.grid.origin_mm);
    check_spacing(h.grid.spacing_mm);
    h.grid.dims = dims(header_);
    h.tools = tool_list(header_);
    h.interpolation = interpolation_of(header_);
    expect_value(header_, "frame", "workpiece");
    expect_value(header_, "units", "mm");
    h.rotation = has_rotation_channels(header_);
    expect_value(header_, "encoding", kEncoding);
    check_memory(h);
    return h;
  }

  LoadedField run() {
    const FieldFileHeader h = header_only();
    const Header& header = header_;
    const FieldGrid& grid = h.grid;
    const std::vector<int32_t>& tools = h.tools;
    const FieldInterpolation interpolation = h.interpolation;
    const bool rotation = h.rotation;

    const uint64_t expected = static_cast<uint64_t>(tools.size()) *
                              static_cast<uint64_t>(grid.node_count()) * bytes_per_node(rotation);
    const auto declared = parse_number<uint64_t>(required(header, "payload_bytes"));
    if (!declared)
      fail("payload_bytes is not a byte count: " + printable(required(header, "payload_bytes")));
    if (*declared != expected)
      fail("dims mismatch: dims " + std::to_string(grid.dims[0]) + "x" +
           std::to_string(grid.dims[1]) + "x" + std::to_string(grid.dims[2]) + " with " +
           std::to_string(tools.size()) + " tool layer(s) need " + std::to_string(expected) +
           " payload bytes, header says payload_bytes " + std::to_string(*declared));
    const std::size_t actual = bytes_.size() - header.payload_offset;
    if (actual < expected)
      fail("truncated payload: expected " + std::to_string(expected) +
           " bytes after end_header, found " + std::to_string(actual));
    if (actual > expected)
      fail(std::to_string(actual - expected) + " unexpected bytes after the " +
           std::to_string(expected) + "-byte payload");
    check_crc(header);

    LoadedField loaded{{header_value(header, "created"), header_value(header, "source"),
                        header_value(header, "machine"), header_value(header, "part"),
                        header_value(header, "tool_set")},
                       make_field(grid, tools, interpolation, rotation, header.payload_offset)};
    loaded.crc64 = *parse_number<uint64_t>(required(header, "crc64"), 16);
    loaded.field.set_identity({loaded.crc64, field_identity_id(loaded.info.machine),
                               field_identity_id(loaded.info.part),
                               field_identity_id(loaded.info.tool_set)});
    return loaded;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw FieldFileError(std::string(name_) + ": " + what);
  }

  std::string at_line(std::string_view key) const {
    const auto it = header_.lines.find(key);
    return it == header_.lines.end() ? std::string() : "line " + std::to_string(it->second) + ": ";
  }

  void check_origin(const Eigen::Vector3d& origin_mm) const {
    for (int a = 0; a < 3; ++a)
      if (!(std::abs(origin_mm[a]) <= kMaxFieldCoordinateMm))
        fail(at_line("origin") + "origin " + format_shortest(origin_mm[a]) + " mm (" + "xyz"[a] +
             ") is outside ±" + format_shortest(kMaxFieldCoordinateMm) +
             " mm (no machine is larger than 100 m; check the unit)");
  }

  void check_spacing(const Eigen::Vector3d& spacing_mm) const {
    for (int a = 0; a < 3; ++a)
      if (!(spacing_mm[a] >= kMinFieldSpacingMm && spacing_mm[a] <= kMaxFieldSpacingMm))
        fail(at_line("spacing") + "spacing " + format_shortest(spacing_mm[a]) + " mm (" + "xyz"[a] +
             ") is outside " + format_shortest(kMinFieldSpacingMm) + " .. " +
             format_shortest(kMaxFieldSpacingMm) +
             " mm (a node spacing from 1 um to 1 m; check the unit)");
  }

  void check_memory(const FieldFileHeader& h) const {
    const uint64_t need = field_load_bytes(h), limit = max_field_load_bytes();
    if (need <= limit) return;
    fail(at_line("dims") + "loading this field would take about " + std::to_string(need >> 20) +
         " MB (" + std::to_string(h.grid.node_count()) + " nodes x " +
         std::to_string(h.tools.size()) + " tool layer(s) x " +
         std::to_string(channel_count(h.rotation)) + " channels), more than the " +
         std::to_string(limit >> 20) +
         " MB a field may take; the environment variable TRUECUT_MAX_FIELD_MB raises the limit");
  }

  Header parse_header() {
    if (bytes_.empty()) fail("empty file, not a truecut correction field");
    Header h;
    std::size_t pos = 0;
    bool first = true;
    bool after_crc = false;
    while (true) {
      const std::size_t eol = bytes_.find('\n', pos);
      if (eol == std::string_view::npos || eol > kMaxHeaderBytes) {
        if (first)
          fail("bad magic: not a truecut correction field (no " + std::string(kMagic) + " line)");
        fail("no end_header line within the first " + std::to_string(kMaxHeaderBytes) + " bytes");
      }
      const std::string_view line = bytes_.substr(pos, eol - pos);
      const std::size_t line_offset = pos;
      pos = eol + 1;
      const std::size_t line_no = ++line_no_;
      if (first) {
        check_magic(trim(line));
        first = false;
        continue;
      }
      if (trim(line) == kEndHeader) {
        if (!after_crc) fail("crc64 must be the last header line before end_header");
        h.payload_offset = pos;
        return h;
      }
      if (after_crc)
        fail("line " + std::to_string(line_no) + ": nothing may follow crc64 but end_header");
      const std::size_t colon = line.find(':');
      if (colon == std::string_view::npos)
        fail("line " + std::to_string(line_no) + ": expected 'key: value', got " + printable(line));
      const std::string key(trim(line.substr(0, colon)));
      if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys))
        fail("line " + std::to_string(line_no) + ": unknown header key " + printable(key));
      if (!h.values.emplace(key, trim(line.substr(colon + 1))).second)
        fail("line " + std::to_string(line_no) + ": header key '" + key + "' given twice");
      h.lines.emplace(key, line_no);
      if (key == "crc64") {
        h.crc_line_offset = line_offset;
        after_crc = true;
      }
    }
  }

  void check_magic(std::string_view line) const {
    const auto words = split_words(line);
    if (words.size() != 2 || words[0] != kMagic)
      fail("bad magic: not a truecut correction field (first line " + printable(line) +
           ", expected '" + std::string(kMagic) + " " + std::to_string(kVersion) + "')");
    if (parse_number<int>(words[1]) != kVersion)
      fail("unsupported version " + printable(words[1]) + "; this reader supports version " +
           std::to_string(kVersion));
  }

  std::string_view required(const Header& h, std::string_view key) const {
    const auto it = h.values.find(key);
    if (it == h.values.end()) fail("missing header key '" + std::string(key) + "'");
    return it->second;
  }

  static std::string header_value(const Header& h, std::string_view key) {
    const auto it = h.values.find(key);
    return it == h.values.end() ? std::string() : it->second;
  }

  bool has_rotation_channels(const Header& h) const {
    const std::string_view value = required(h, "channels");
    const auto got = split_words(value);
    if (got == split_words(kChannels)) return false;
    if (got == split_words(kChannelsWithRotation)) return true;
    fail("channels is " + printable(value) + ", must be '" + std::string(kChannels) + "' or '" +
         std::string(kChannelsWithRotation) + "'");
  }

  void expect_value(const Header& h, std::string_view key, std::string_view want) const {
    const std::string_view value = required(h, key);
    const auto got = split_words(value), expected = split_words(want);
    if (got != expected)
      fail(std::string(key) + " is " + printable(value) + ", must be '" + std::string(want) + "'");
  }

  Eigen::Vector3d vector3(const Header& h, std::string_view key) const {
    const std::string_view value = required(h, key);
    const auto words = split_words(value);
    Eigen::Vector3d v;
    for (std::size_t a = 0; a < 3; ++a) {
      const auto x = words.size() == 3 ? parse_number<double>(words[a]) : std::nullopt;
      if (!x || !std::isfinite(*x))
        fail(std::string(key) + " must be three finite numbers (mm), is " + printable(value));
      v[static_cast<int>(a)] = *x;
    }
    return v;
  }

  std::array<int32_t, 3> dims(const Header& h) const {
    const std::string_view value = required(h, "dims");
    const auto words = split_words(value);
    std::array<int32_t, 3> d{};
    for (std::size_t a = 0; a < 3; ++a) {
      const auto n = words.size() == 3 ? parse_number<int32_t>(words[a]) : std::nullopt;
      if (!n || *n < 2) fail("dims must be three node counts >= 2, is " + printable(value));
      d[a] = *n;
    }
    if (int64_t{d[0]} * d[1] * d[2] > CorrectionField::kMaxNodes)
      fail("dims " + printable(value) + " exceed " + std::to_string(CorrectionField::kMaxNodes) +
           " nodes per layer");
    return d;
  }

  std::vector<int32_t> tool_list(const Header& h) const {
    const std::string_view value = required(h, "tools");
    std::vector<int32_t> tools;
    for (const std::string_view word : split_words(value)) {
      const auto t = parse_number<int32_t>(word);
      if (!t || *t < 0) fail("tools must be tool numbers >= 0, got " + printable(word));
      if (std::find(tools.begin(), tools.end(), *t) != tools.end())
        fail("tool " + std::to_string(*t) + " listed twice in tools");
      tools.push_back(*t);
    }
    if (tools.empty()) fail("tools lists no tool");
    if (tools.size() > CorrectionField::kMaxLayers)
      fail(std::to_string(tools.size()) + " tools, at most " +
           std::to_string(CorrectionField::kMaxLayers));
    return tools;
  }

  FieldInterpolation interpolation_of(const Header& h) const {
    const std::string_view value = required(h, "interpolation");
    for (const auto mode : {FieldInterpolation::kTricubicBspline, FieldInterpolation::kTrilinear})
      if (value == to_string(mode)) return mode;
    fail("interpolation " + printable(value) +
         " unknown; expected 'tricubic-bspline' or 'trilinear'");
  }

  void check_crc(const Header& h) const {
    const std::string_view text = required(h, "crc64");
    const auto stated = text.size() == 16 ? parse_number<uint64_t>(text, 16) : std::nullopt;
    if (!stated) fail("crc64 must be 16 hex digits, is " + printable(text));
    Crc64 crc;
    crc.update(bytes_.substr(0, h.crc_line_offset));
    crc.update(bytes_.substr(h.payload_offset));
    if (crc.value() != *stated)
      fail("checksum mismatch: header says crc64 " + std::string(text) +
           ", header and payload give " + format_hex64(crc.value()) + "; the file is corrupted");
  }

  CorrectionField make_field(const FieldGrid& grid, const std::vector<int32_t>& tools,
                             FieldInterpolation interpolation, bool rotation,
                             std::size_t offset) const {
    std::vector<FieldLayer> layers;
    layers.reserve(tools.size());
    const char* p = bytes_.data() + offset;
    const int channels = channel_count(rotation);
    const auto nodes = static_cast<std::size_t>(grid.node_count());
    for (std::size_t l = 0; l < tools.size(); ++l) {
      FieldLayer layer{tools[l], std::vector<FieldNode>(nodes)};
      if (rotation) layer.rotation_rad.resize(nodes);
      for (int64_t n = 0; n < grid.node_count(); ++n) {
        double v[7];
        for (int c = 0; c < channels; ++c, p += sizeof(double)) {
          v[c] = get_le(p);
          const bool bad = c < channels - 1 ? !std::isfinite(v[c]) : !(v[c] >= 0.0 && v[c] <= 1.0);
          if (bad)
            fail(bad_value_message(grid, tools, l, n, rotation, c, v[c],
                                   p - bytes_.data() - offset));
        }
        layer.nodes[static_cast<std::size_t>(n)] = {v[0], v[1], v[2], v[channels - 1]};
        if (rotation) layer.rotation_rad[static_cast<std::size_t>(n)] = {v[3], v[4], v[5]};
      }
      layers.push_back(std::move(layer));
    }
    try {
      return CorrectionField(grid, std::move(layers), interpolation);
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
  }

  static std::string bad_value_message(const FieldGrid& grid, const std::vector<int32_t>& tools,
                                       std::size_t layer, int64_t node, bool rotation, int channel,
                                       double value, std::ptrdiff_t payload_offset) {
    const int64_t i = node % grid.dims[0], j = (node / grid.dims[0]) % grid.dims[1],
                  k = node / (int64_t{grid.dims[0]} * grid.dims[1]);
    std::ostringstream s;
    const bool weight = channel == channel_count(rotation) - 1;
    s << (weight ? "weight outside [0, 1]: " : "non-finite value ") << value
      << " in payload: layer " << layer << " (tool " << tools[layer] << "), node (i, j, k) = (" << i
      << ", " << j << ", " << k << "), channel "
      << (rotation ? kChannelNamesWithRotation[channel] : kChannelNames[channel])
      << ", payload byte offset " << payload_offset;
    return s.str();
  }

  std::string_view bytes_;
  std::string_view name_;
  std::size_t line_no_ = 0;
  Header header_;
};

void check_one_line(const std::string& what, const std::string& value) {
  if (value.find_first_of("\r\n") != std::string::npos)
    throw FieldFileError("field file " + what + " must be a single line: " + printable(value));
}

// ------------------------------------------------------------ file output

}  // namespace

uint32_t field_identity_id(std::string_view text) noexcept {
  if (text.empty()) return 0;
  Crc64 crc;
  crc.update(text);
  const auto id = static_cast<uint32_t>(crc.value());
  return id == 0 ? 1u : id;
}

std::string encode_field_file(const CorrectionField& field, const FieldFileInfo& info) {
  check_one_line("created", info.created);
  check_one_line("source", info.source);
  check_one_line("machine", info.machine);
  check_one_line("part", info.part);
  check_one_line("tool_set", info.tool_set);

  const FieldGrid& g = field.grid();
  auto triple = [](const Eigen::Vector3d& v) {
    return format_shortest(v.x()) + " " + format_shortest(v.y()) + " " + format_shortest(v.z());
  };
  std::string tools;
  for (const int32_t t : field.tools())
    tools += (tools.empty() ? "" : " ") + std::to_string(t);

  const bool rotation = field.has_rotation();
  std::string payload(
      field.tools().size() * static_cast<std::size_t>(g.node_count()) * bytes_per_node(rotation),
      '\0');
  char* at = payload.data();
  for (const int32_t t : field.tools()) {
    const std::span<const FieldNode> nodes = field.nodes(t);
    const std::span<const Eigen::Vector3d> rotations = field.rotations(t);
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      put_le(at, nodes[n].dx_mm);
      put_le(at, nodes[n].dy_mm);
      put_le(at, nodes[n].dz_mm);
      if (rotation)
        for (int c = 0; c < 3; ++c)
          put_le(at, rotations[n][c]);
      put_le(at, nodes[n].weight);
    }
  }

  std::string header = std::string(kMagic) + " " + std::to_string(kVersion) + "\n";
  header += "frame: workpiece\nunits: mm\n";
  header += "origin: " + triple(g.origin_mm) + "\n";
  header += "spacing: " + triple(g.spacing_mm) + "\n";
  header += "dims: " + std::to_string(g.dims[0]) + " " + std::to_string(g.dims[1]) + " " +
            std::to_string(g.dims[2]) + "\n";
  header += "tools: " + tools + "\n";
  header += "interpolation: " + std::string(to_string(field.interpolation())) + "\n";
  header += "channels: " + std::string(rotation ? kChannelsWithRotation : kChannels) + "\n";
  header += "encoding: " + std::string(kEncoding) + "\n";
  header += "created: " + (info.created.empty() ? utc_timestamp_now() : info.created) + "\n";
  header += "source: " + info.source + "\n";
  if (!info.machine.empty()) header += "machine: " + info.machine + "\n";
  if (!info.part.empty()) header += "part: " + info.part + "\n";
  if (!info.tool_set.empty()) header += "tool_set: " + info.tool_set + "\n";
  header += "payload_bytes: " + std::to_string(payload.size()) + "\n";
  Crc64 crc;
  crc.update(header);
  crc.update(payload);
  header += "crc64: " + format_hex64(crc.value()) + "\n";
  header += std::string(kEndHeader) + "\n";
  return header + payload;
}

uint64_t field_load_bytes(const FieldFileHeader& h) noexcept {
  // Measured: the file's bytes, the layers read from them, and while the
  // field is built the prefilter's vectors, steps and coefficients (a
  // 250 MB translation field peaked at 950 MB).
  const uint64_t per_node = h.rotation ? 240 : 136;
  return static_cast<uint64_t>(h.grid.node_count()) * h.tools.size() * per_node;
}

uint64_t max_field_load_bytes() {
  const char* env = std::getenv("TRUECUT_MAX_FIELD_MB");
  if (!env || !*env) return kDefaultMaxFieldLoadMb << 20;
  char* end = nullptr;
  errno = 0;
  const unsigned long long mb = std::strtoull(env, &end, 10);
  if (*end != '\0' || errno != 0 || mb == 0 || mb > (1ull << 40))
    throw FieldFileError(std::string("TRUECUT_MAX_FIELD_MB='") + env +
                         "' must be a whole number of MB from 1 to 2^40");
  return static_cast<uint64_t>(mb) << 20;
}

LoadedField decode_field_file(std::string_view bytes, std::string_view name) {
  return Decoder(bytes, name).run();
}

FieldFileHeader decode_field_file_header(std::string_view bytes, std::string_view name) {
  return Decoder(bytes, name).header_only();
}

FieldFileHeader read_field_file_header(const std::filesystem::path& path) {
  try {
    check_input_file(path, "correction field");
  } catch (const InputFileError& e) {
    throw FieldFileError(e.what());
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FieldFileError(path.string() + ": cannot open the correction field");
  std::string head(kMaxHeaderBytes + 1, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return decode_field_file_header(head, path.string());
}

LoadedField read_field_file(const std::filesystem::path& path) {
  // The header first: a field too large to load is refused before its
  // payload is read.
  (void)read_field_file_header(path);
  std::string bytes;
  try {
    bytes = read_input_file(path, "correction field");
  } catch (const InputFileError& e) {
    throw FieldFileError(e.what());
  }
  return decode_field_file(bytes, path.string());
}

void write_field_file(const std::filesystem::path& path, const CorrectionField& field,
                      const FieldFileInfo& info) {
  const std::string bytes = encode_field_file(field, info);
  try {
    write_file_atomically(path, bytes);
  } catch (const FileWriteError& e) {
    throw FieldFileError(e.what());
  }
}

}  // namespace truecut::rt
