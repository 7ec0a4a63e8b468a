#include "truecut/rt/field_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "test_paths.hpp"

namespace truecut::rt {
namespace {

namespace fs = std::filesystem;

CorrectionField sample_field(
    FieldInterpolation interpolation = FieldInterpolation::kTricubicBspline) {
  FieldGrid g;
  g.origin_mm = {-10.1, 0.3, -42.000000000000007};  // not exactly representable: must round-trip
  g.spacing_mm = {2.5, 1.0 / 3.0, 1.25};
  g.dims = {4, 3, 5};
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> d(-0.2, 0.2), w(0.0, 1.0);
  std::vector<FieldLayer> layers;
  for (const int32_t tool : {7, 2}) {
    FieldLayer layer{tool, {}};
    for (int64_t n = 0; n < g.node_count(); ++n)
      layer.nodes.push_back({d(rng), d(rng), d(rng), w(rng)});
    layers.push_back(std::move(layer));
  }
  return CorrectionField(g, std::move(layers), interpolation);
}

const FieldFileInfo kInfo{"2026-11-21T09:30:00Z", "unit test: random field, seed 99"};

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

std::size_t payload_offset(const std::string& bytes) {
  const std::string marker = "\nend_header\n";
  return bytes.find(marker) + marker.size();
}

// Recomputes the crc64 line after a deliberate edit, so that a test reaches
// the validation behind the checksum.
std::string with_fresh_crc(std::string bytes) {
  const std::size_t line = bytes.find("crc64: ");
  const std::size_t payload = payload_offset(bytes);
  Crc64 crc;
  crc.update(std::string_view(bytes).substr(0, line));
  crc.update(std::string_view(bytes).substr(payload));
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(crc.value()));
  bytes.replace(line + 7, 16, hex);
  return bytes;
}

void replace_once(std::string& text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

// Decoding `bytes` must fail with a message naming the file and containing
// every fragment.
void expect_error(const std::string& bytes, std::initializer_list<std::string> fragments) {
  try {
    decode_field_file(bytes, "part7.tcf");
    ADD_FAILURE() << "decoded; expected an error";
  } catch (const FieldFileError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("part7.tcf: ", 0), 0u) << what;
    for (const std::string& f : fragments)
      EXPECT_NE(what.find(f), std::string::npos) << what;
  }
}

void expect_same_field(const CorrectionField& a, const CorrectionField& b) {
  EXPECT_EQ(a.grid().origin_mm, b.grid().origin_mm);
  EXPECT_EQ(a.grid().spacing_mm, b.grid().spacing_mm);
  EXPECT_EQ(a.grid().dims, b.grid().dims);
  EXPECT_EQ(a.interpolation(), b.interpolation());
  ASSERT_TRUE(std::equal(a.tools().begin(), a.tools().end(), b.tools().begin(), b.tools().end()));
  for (const int32_t t : a.tools()) {
    const auto na = a.nodes(t), nb = b.nodes(t);
    ASSERT_EQ(na.size(), nb.size());
    for (std::size_t n = 0; n < na.size(); ++n) {
      EXPECT_EQ(std::memcmp(&na[n], &nb[n], sizeof(FieldNode)), 0) << "tool " << t << " node " << n;
    }
  }
}

TEST(Crc64, CheckValue) {
  Crc64 crc;
  crc.update("123456789");
  EXPECT_EQ(crc.value(), 0x995dc9bbdf1939faull);
  Crc64 split;
  split.update("1234");
  split.update("56789");
  EXPECT_EQ(split.value(), crc.value());
  EXPECT_EQ(Crc64{}.value(), 0u);
}

// Against the bit-by-bit definition (CRC-64/XZ), at every length and
// alignment the eight-bytes-a-step loop and its tail meet.
TEST(Crc64, AgreesWithTheBitwiseDefinition) {
  const auto bitwise = [](std::string_view bytes) {
    std::uint64_t crc = ~std::uint64_t{0};
    for (const char ch : bytes) {
      crc ^= static_cast<unsigned char>(ch);
      for (int bit = 0; bit < 8; ++bit)
        crc = (crc & 1) ? (crc >> 1) ^ 0xC96C5795D7870F42ull : crc >> 1;
    }
    return ~crc;
  };
  std::string data;
  std::uint64_t x = 0x9e3779b97f4a7c15ull;
  for (int i = 0; i < 300; ++i) {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    data.push_back(static_cast<char>(x & 0xFF));
  }
  for (std::size_t offset = 0; offset < 9; ++offset) {
    for (std::size_t length = 0; offset + length <= data.size(); length += 7) {
      const std::string_view part = std::string_view(data).substr(offset, length);
      Crc64 crc;
      crc.update(part.substr(0, length / 3));
      crc.update(part.substr(length / 3));
      ASSERT_EQ(crc.value(), bitwise(part)) << "offset " << offset << " length " << length;
    }
  }
}

TEST(FieldFile, RoundTripThroughAFile) {
  const fs::path path = test::scratch_dir() / "field.tcf";
  for (const auto mode : {FieldInterpolation::kTricubicBspline, FieldInterpolation::kTrilinear}) {
    const CorrectionField field = sample_field(mode);
    write_field_file(path, field, kInfo);
    EXPECT_FALSE(fs::exists(path.string() + ".tmp"));
    const LoadedField loaded = read_field_file(path);
    EXPECT_EQ(loaded.info.created, kInfo.created);
    EXPECT_EQ(loaded.info.source, kInfo.source);
    expect_same_field(field, loaded.field);
    const Eigen::Vector3d p = field.grid().origin_mm + Eigen::Vector3d(3.3, 0.4, 2.2);
    EXPECT_EQ(field.evaluate(7, p).correction_mm, loaded.field.evaluate(7, p).correction_mm);
  }
}

TEST(FieldFile, HeaderIsReadableText) {
  const std::string bytes = encode_field_file(sample_field(), kInfo);
  const std::string header = bytes.substr(0, payload_offset(bytes));
  EXPECT_EQ(header.rfind("TRUECUT-FIELD 1\nframe: workpiece\nunits: mm\n", 0), 0u) << header;
  for (const char* line :
       {"\ndims: 4 3 5\n", "\ntools: 2 7\n", "\ninterpolation: tricubic-bspline\n",
        "\nchannels: dx dy dz weight\n", "\nencoding: float64-le\n",
        "\ncreated: 2026-11-21T09:30:00Z\n", "\nsource: unit test: random field, seed 99\n",
        "\npayload_bytes: 3840\n", "\nspacing: 2.5 0.3333333333333333 1.25\n"})
    EXPECT_NE(header.find(line), std::string::npos) << line << "\nin\n" << header;
  EXPECT_EQ(bytes.size() - header.size(), 2u * 60u * 4u * 8u);
}

TEST(FieldFile, PayloadIsLittleEndianFloat64InDocumentedOrder) {
  const CorrectionField field = sample_field();
  const std::string bytes = encode_field_file(field, kInfo);
  const std::size_t payload = payload_offset(bytes);
  // Tool 7 is second in ascending order; node (i, j, k) = (1, 2, 3); channel dz.
  const int64_t node = field.grid().index(1, 2, 3);
  const std::size_t at = payload + (60 + node) * 32 + 2 * 8;
  uint64_t bits = 0;
  for (int b = 7; b >= 0; --b)
    bits = (bits << 8) | static_cast<unsigned char>(bytes[at + b]);
  double value;
  std::memcpy(&value, &bits, sizeof value);
  EXPECT_EQ(value, field.nodes(7)[node].dz_mm);
}

TEST(FieldFile, WriterReplacesAnExistingFileAndFillsInTheDate) {
  const fs::path path = test::scratch_dir() / "field.tcf";
  write_bytes(path, "old contents");
  write_field_file(path, sample_field(), {"", "no date given"});
  const LoadedField loaded = read_field_file(path);
  const std::string& created = loaded.info.created;
  ASSERT_EQ(created.size(), 20u) << created;
  EXPECT_EQ(created[4], '-');
  EXPECT_EQ(created[10], 'T');
  EXPECT_EQ(created.back(), 'Z');
  EXPECT_GE(created.substr(0, 4), "2024");
}

TEST(FieldFile, WriterReportsUnwritableDestination) {
  const fs::path path = test::scratch_dir() / "no-such-dir" / "field.tcf";
  try {
    write_field_file(path, sample_field(), kInfo);
    ADD_FAILURE() << "wrote into a missing directory";
  } catch (const FieldFileError& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-dir/field.tcf.tmp"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(encode_field_file(sample_field(), {"", "two\nlines"}), FieldFileError);
}

TEST(FieldFile, MissingFileNamesThePath) {
  const fs::path path = test::scratch_dir() / "absent.tcf";
  try {
    read_field_file(path);
    ADD_FAILURE() << "read a missing file";
  } catch (const FieldFileError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.tcf: cannot open"), std::string::npos) << e.what();
  }
}

TEST(FieldFile, AnyFlippedPayloadByteIsACheckSumError) {
  const std::string good = encode_field_file(sample_field(), kInfo);
  const std::size_t payload = payload_offset(good);
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<std::size_t> where(payload, good.size() - 1);
  std::uniform_int_distribution<int> bit(0, 7);
  for (int n = 0; n < 200; ++n) {
    std::string bad = good;
    bad[where(rng)] ^= static_cast<char>(1 << bit(rng));
    expect_error(bad, {"checksum mismatch"});
  }
  std::string last = good;
  last.back() ^= 0x01;
  expect_error(last, {"checksum mismatch"});
}

TEST(FieldFile, FlippedHeaderByteIsDetected) {
  std::string bad = encode_field_file(sample_field(), kInfo);
  replace_once(bad, "origin: -10.1 ", "origin: -11.1 ");  // still a valid header
  expect_error(bad, {"checksum mismatch"});
}

TEST(FieldFile, TruncatedOrPaddedPayload) {
  const std::string good = encode_field_file(sample_field(), kInfo);
  expect_error(good.substr(0, good.size() - 1), {"truncated payload", "3840", "3839"});
  expect_error(good.substr(0, payload_offset(good)), {"truncated payload", "found 0"});
  expect_error(good + "xyz", {"3 unexpected bytes after the 3840-byte payload"});
  expect_error(good.substr(0, 40), {"no end_header"});
}

TEST(FieldFile, BadMagicAndVersion) {
  const std::string good = encode_field_file(sample_field(), kInfo);
  expect_error("", {"empty file"});
  expect_error("ply\nformat binary_little_endian 1.0\n", {"bad magic", "'ply'"});
  std::string v2 = good;
  replace_once(v2, "TRUECUT-FIELD 1\n", "TRUECUT-FIELD 2\n");
  expect_error(v2, {"unsupported version '2'", "supports version 1"});
}

TEST(FieldFile, HeaderKeysAreChecked) {
  const std::string good = encode_field_file(sample_field(), kInfo);
  auto edited = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    replace_once(s, from, to);
    return with_fresh_crc(s);
  };
  expect_error(edited("units: mm\n", ""), {"missing header key 'units'"});
  expect_error(edited("units: mm\n", "units: inch\n"), {"units is 'inch', must be 'mm'"});
  expect_error(edited("frame: workpiece\n", "frame: machine\n"), {"frame"});
  expect_error(edited("units: mm\n", "units: mm\ncolour: blue\n"), {"unknown header key 'colour'"});
  expect_error(edited("units: mm\n", "units: mm\nunits: mm\n"), {"'units' given twice"});
  expect_error(edited("tools: 2 7\n", "tools: 2 2\n"), {"tool 2 listed twice"});
  expect_error(edited("interpolation: tricubic-bspline\n", "interpolation: nurbs\n"),
               {"interpolation 'nurbs' unknown"});
  expect_error(edited("encoding: float64-le\n", "encoding: float32-le\n"), {"encoding"});
  expect_error(edited("dims: 4 3 5\n", "dims: 4 3 1\n"), {"dims must be three node counts >= 2"});
  expect_error(edited("spacing: 2.5 ", "spacing: nan "), {"spacing must be three finite numbers"});
  expect_error(edited("dims: 4 3 5\n", "dims: 4 3 x\n"), {"dims"});
  std::string crc_first = good;
  const std::size_t crc_line = crc_first.find("crc64: ");
  const std::string line = crc_first.substr(crc_line, 24);
  crc_first.erase(crc_line, 24);
  replace_once(crc_first, "units: mm\n", "units: mm\n" + line);
  expect_error(crc_first, {"nothing may follow crc64"});
}

TEST(FieldFile, DimsMismatchNamesTheByteCounts) {
  std::string bad = encode_field_file(sample_field(), kInfo);
  replace_once(bad, "dims: 4 3 5\n", "dims: 4 3 6\n");
  expect_error(with_fresh_crc(bad),
               {"dims mismatch", "4x3x6", "2 tool layer(s) need 4608", "payload_bytes 3840"});
  std::string tools = encode_field_file(sample_field(), kInfo);
  replace_once(tools, "tools: 2 7\n", "tools: 2\n");
  expect_error(with_fresh_crc(tools), {"dims mismatch", "1920"});
}

TEST(FieldFile, NonFinitePayloadValueNamesLayerNodeAndChannel) {
  const CorrectionField field = sample_field();
  std::string bad = encode_field_file(field, kInfo);
  const int64_t node = field.grid().index(2, 1, 4);
  const std::size_t at = payload_offset(bad) + (60 + node) * 32 + 1 * 8;  // tool 7, dy
  const double nan = std::nan("");
  std::memcpy(&bad[at], &nan, sizeof nan);  // NaN bytes are symmetric enough; endianness moot
  // The offset of the value itself (issue 23: the first value was reported at -8).
  expect_error(with_fresh_crc(bad),
               {"non-finite value nan", "layer 1 (tool 7)", "node (i, j, k) = (2, 1, 4)",
                "channel dy", "payload byte offset " + std::to_string(at - payload_offset(bad))});

  std::string heavy = encode_field_file(field, kInfo);
  const double w = 1.25;
  uint64_t bits;
  std::memcpy(&bits, &w, sizeof w);
  const std::size_t wat = payload_offset(heavy) + 0 * 32 + 3 * 8;  // tool 2, node 0, weight
  for (int b = 0; b < 8; ++b, bits >>= 8)
    heavy[wat + b] = static_cast<char>(bits & 0xFF);
  expect_error(with_fresh_crc(heavy),
               {"weight outside [0, 1]: 1.25", "layer 0 (tool 2)", "node (i, j, k) = (0, 0, 0)",
                "channel weight", "payload byte offset 24"});
}

TEST(FieldFile, ToleratesCarriageReturnsInTheHeader) {
  // A header that went through a Windows editor still reads, as long as its
  // checksum was refreshed for the new bytes.
  std::string bytes = encode_field_file(sample_field(), kInfo);
  replace_once(bytes, "units: mm\n", "units: mm\r\n");
  EXPECT_NO_THROW(decode_field_file(with_fresh_crc(bytes), "crlf.tcf"));
}

}  // namespace
}  // namespace truecut::rt

namespace truecut::rt {
namespace {

TEST(FieldFile, IdentityRoundTripsAndIsOptional) {
  // Issue 19, point 5: the field names the machine, part and tool set it
  // was built for; files without them read as before.
  FieldFileInfo info = kInfo;
  info.machine = "umc-750 #2";
  info.part = "implant rev C";
  info.tool_set = "T3 ball 6 mm, T7 flat 10 mm";
  const std::string bytes = encode_field_file(sample_field(), info);
  EXPECT_NE(std::string::npos, bytes.find("\nmachine: umc-750 #2\npart: implant rev C\n"
                                          "tool_set: T3 ball 6 mm, T7 flat 10 mm\n"));
  const LoadedField loaded = decode_field_file(bytes, "named.tcf");
  EXPECT_EQ(info.machine, loaded.info.machine);
  EXPECT_EQ(info.part, loaded.info.part);
  EXPECT_EQ(info.tool_set, loaded.info.tool_set);
  const FieldIdentity& id = loaded.field.identity();
  EXPECT_EQ(field_identity_id(info.machine), id.machine);
  EXPECT_EQ(field_identity_id(info.part), id.part);
  EXPECT_EQ(field_identity_id(info.tool_set), id.tool_set);
  EXPECT_NE(0u, id.machine);
  EXPECT_NE(id.machine, id.part);
  // The CRC is the one in the header.
  const std::size_t at = bytes.find("\ncrc64: ") + 8;
  EXPECT_EQ(std::stoull(bytes.substr(at, 16), nullptr, 16), loaded.crc64);
  EXPECT_EQ(loaded.crc64, id.crc64);
  // Unnamed: no keys, ids 0, the crc still there.
  const std::string plain = encode_field_file(sample_field(), kInfo);
  EXPECT_EQ(std::string::npos, plain.find("machine:"));
  const LoadedField old = decode_field_file(plain, "plain.tcf");
  EXPECT_EQ(0u, old.field.identity().machine);
  EXPECT_EQ(0u, old.field.identity().tool_set);
  EXPECT_NE(0u, old.crc64);
  EXPECT_EQ(0u, field_identity_id(""));
  // CRC-64/XZ of "123456789" is 0x995dc9bbdf1939fa: the id is its low half.
  EXPECT_EQ(0xdf1939fau, field_identity_id("123456789"));
  EXPECT_THROW(encode_field_file(sample_field(), {"", "", "two\nlines"}), FieldFileError);
}

}  // namespace
}  // namespace truecut::rt

namespace truecut::rt {
namespace {

// Issue 23: a grid 1e300 mm away or 1e-300 mm fine was read, and the field
// corrected nothing with exit 0. Refused at the header line.
TEST(FieldFile, AnOriginOrSpacingBeyondAnyMachineIsRefusedAtItsLine) {
  const std::string good = encode_field_file(sample_field(), kInfo);
  auto edited = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    replace_once(s, from, to);
    return with_fresh_crc(s);
  };
  expect_error(edited("origin: -10.1 ", "origin: 1e300 "),
               {"line 4: origin 1e+300 mm (x) is outside ±1e+05 mm"});
  expect_error(edited("spacing: 2.5 ", "spacing: 1e-300 "),
               {"line 5: spacing 1e-300 mm (x) is outside 0.001 .. 1000 mm"});
  expect_error(edited("spacing: 2.5 ", "spacing: 5000 "), {"line 5: spacing 5000 mm (x)"});
  EXPECT_NO_THROW(decode_field_file(good, "part7.tcf"));
}

// Issue 23: a 1 GB field (inside the input budget and the nodes per layer)
// needed about 4 GB to load, and ended in std::bad_alloc. The header says
// what loading takes; the payload need not even be read.
TEST(FieldFile, AFieldTooLargeToLoadIsRefusedFromItsHeader) {
  std::string big = encode_field_file(sample_field(), kInfo);
  replace_once(big, "dims: 4 3 5\n", "dims: 1024 1024 30\n");
  big.resize(payload_offset(big));  // the header alone
  for (const bool header_only : {true, false}) {
    try {
      if (header_only)
        (void)decode_field_file_header(big, "big.tcf");
      else
        (void)decode_field_file(big, "big.tcf");
      ADD_FAILURE() << "a field of 2 x 31 million nodes was accepted";
    } catch (const FieldFileError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("big.tcf: line 6: loading this field would take about 8160 MB "
                          "(31457280 nodes x 2 tool layer(s) x 4 channels), more than the "
                          "3072 MB a field may take; the environment variable "
                          "TRUECUT_MAX_FIELD_MB raises the limit"),
                std::string::npos)
          << what;
    }
  }
  const FieldFileHeader h = decode_field_file_header(encode_field_file(sample_field(), kInfo), "f");
  EXPECT_EQ((std::array<int32_t, 3>{4, 3, 5}), h.grid.dims);
  EXPECT_EQ((std::vector<int32_t>{2, 7}), h.tools);
  EXPECT_FALSE(h.rotation);
}

TEST(FieldFile, TheLoadBudgetIsRaisedByTheEnvironment) {
  std::string big = encode_field_file(sample_field(), kInfo);
  replace_once(big, "dims: 4 3 5\n", "dims: 1024 1024 30\n");
  big.resize(payload_offset(big));
  ::setenv("TRUECUT_MAX_FIELD_MB", "9000", 1);
  // Past the budget: the payload is checked, and is missing.
  EXPECT_THROW(
      {
        try {
          (void)decode_field_file(big, "big.tcf");
        } catch (const FieldFileError& e) {
          EXPECT_NE(std::string(e.what()).find("payload"), std::string::npos) << e.what();
          throw;
        }
      },
      FieldFileError);
  ::setenv("TRUECUT_MAX_FIELD_MB", "many", 1);
  EXPECT_THROW((void)decode_field_file_header(big, "big.tcf"), FieldFileError);
  ::unsetenv("TRUECUT_MAX_FIELD_MB");
}

}  // namespace
}  // namespace truecut::rt
