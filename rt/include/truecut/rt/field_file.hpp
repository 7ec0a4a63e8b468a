// Reading and writing correction fields as `.tcf` files (format: the section
// "Correction field (.tcf)" of docs/formats.md). Not real-time: load a field
// here, then hand the CorrectionField to the real-time side by pointer.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "truecut/rt/core/correction_field.hpp"

namespace truecut::rt {

// Every message names the file and what is wrong with it.
class FieldFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Free-text header entries. frame (workpiece) and units (mm) are fixed by
// the format.
struct FieldFileInfo {
  std::string created;  // ISO 8601; when writing, empty means "now" (UTC)
  std::string source;   // what produced the field; one line
  // What the field was built for (one line each; empty: not named, and the
  // key is not written, so such a file is byte for byte what it was before
  // these keys existed).
  std::string machine = {};
  std::string part = {};
  std::string tool_set = {};
};

struct LoadedField {
  FieldFileInfo info;
  CorrectionField field;  // its identity() set from the file
  uint64_t crc64 = 0;     // the file's checksum
};

// The 32-bit id of a machine, part or tool-set name, as truecut_comp shows
// and checks it: the low 32 bits of the CRC-64/XZ of the text, 0 for an
// empty text (and 1 for a text whose low bits are 0).
uint32_t field_identity_id(std::string_view text) noexcept;

// A field's header: what it covers and which tools it has layers for.
struct FieldFileHeader {
  FieldGrid grid;
  std::vector<int32_t> tools;  // in file order
  FieldInterpolation interpolation = FieldInterpolation::kTricubicBspline;
  bool rotation = false;  // the rotation channels rx ry rz
};

// Where a field's grid may lie: the range of a real machine. The reader
// refuses an origin or spacing outside, at its header line (a grid 1e300 mm
// away or 1e-300 mm fine corrected nothing, without a word).
inline constexpr double kMaxFieldCoordinateMm = 1e5;  // no machine is larger than 100 m
inline constexpr double kMinFieldSpacingMm = 1e-3;    // 1 um
inline constexpr double kMaxFieldSpacingMm = 1e3;     // 1 m

// Loading a field takes about 4x its file (the bytes, the layers, the
// prefilter); a field that would take more than max_field_load_bytes() is
// refused from its header, naming the file, the estimate and the limit:
// $TRUECUT_MAX_FIELD_MB (a positive whole number of MB) or this default.
// 3072 MB hold one layer of 2^24 nodes, `truecut field`'s default
// --max-grid-nodes.
inline constexpr uint64_t kDefaultMaxFieldLoadMb = 3072;
uint64_t field_load_bytes(const FieldFileHeader& header) noexcept;
uint64_t max_field_load_bytes();  // throws FieldFileError for a malformed variable

LoadedField read_field_file(const std::filesystem::path& path);
// `name` is used in error messages in place of a path.
LoadedField decode_field_file(std::string_view bytes, std::string_view name);
// Only the header (its first 64 KB are read), checked as read_field_file
// checks it, the memory budget included; the payload is not looked at.
FieldFileHeader read_field_file_header(const std::filesystem::path& path);
FieldFileHeader decode_field_file_header(std::string_view bytes, std::string_view name);

// Writes PATH.tmp, flushes it to disk, then renames it over `path`, so that a
// reader sees either the old file or the complete new one.
void write_field_file(const std::filesystem::path& path, const CorrectionField& field,
                      const FieldFileInfo& info);
std::string encode_field_file(const CorrectionField& field, const FieldFileInfo& info);

// CRC-64/XZ (ECMA-182 polynomial 0x42F0E1EBA9EA3693, reflected, initial value
// and final XOR all ones). Check value for "123456789": 0x995dc9bbdf1939fa.
class Crc64 {
 public:
  void update(std::string_view bytes) noexcept;
  uint64_t value() const noexcept { return ~state_; }

 private:
  uint64_t state_ = ~uint64_t{0};
};

}  // namespace truecut::rt
