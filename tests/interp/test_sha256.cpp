#include "truecut/interp/sha256.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "test_paths.hpp"

namespace truecut::interp {
namespace {

namespace fs = std::filesystem;

// FIPS 180-2 / NIST example vectors.
TEST(Sha256, KnownVectors) {
  EXPECT_EQ("e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855", sha256_hex(""));
  EXPECT_EQ("ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad", sha256_hex("abc"));
  EXPECT_EQ("248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1",
            sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"));
  EXPECT_EQ("cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0",
            sha256_hex(std::string(1000000, 'a')));
}

TEST(Sha256, FileEqualsBytesAcrossReadPieces) {
  const fs::path dir = truecut::test::scratch_dir();
  const std::string bytes = std::string(1000000, 'a') + std::string(1 << 20, '\0') + "tail";
  std::ofstream(dir / "f.bin", std::ios::binary) << bytes;
  EXPECT_EQ(sha256_hex(bytes), sha256_file_hex(dir / "f.bin"));
  std::ofstream(dir / "abc.txt", std::ios::binary) << "abc";
  EXPECT_EQ("ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad",
            sha256_file_hex(dir / "abc.txt"));
}

TEST(Sha256, MissingFileNamesIt) {
  const fs::path missing = truecut::test::scratch_dir() / "missing.bin";
  try {
    sha256_file_hex(missing);
    FAIL() << "hashed a missing file";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(missing.string() + ": cannot open to compute its SHA-256", std::string(e.what()));
  }
}

}  // namespace
}  // namespace truecut::interp
