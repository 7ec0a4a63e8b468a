// SHA-256 (OpenSSL EVP) as 64 lower-case hex digits, for the audit records of
// `truecut rewrite` and `truecut field`: one implementation for every module
// (interp is the lowest that both users depend on; rt does not need it).
//
//   sha256_hex("abc")  "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
//   sha256_file_hex("out/field.tcf")
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace truecut::interp {

// Throws std::runtime_error when OpenSSL fails.
std::string sha256_hex(std::string_view bytes);

// The file's bytes, read in pieces. Throws std::runtime_error
// "FILE: cannot open to compute its SHA-256" / "FILE: read error".
std::string sha256_file_hex(const std::filesystem::path& file);

}  // namespace truecut::interp
