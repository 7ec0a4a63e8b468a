// Reading and writing correction fields as `.tcf` files (format: the section
// "Correction field (.tcf)" of docs/formats.md). Not real-time: load a field
// here, then hand the CorrectionField to the real-time side by pointer.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

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

LoadedField read_field_file(const std::filesystem::path& path);
// `name` is used in error messages in place of a path.
LoadedField decode_field_file(std::string_view bytes, std::string_view name);

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
