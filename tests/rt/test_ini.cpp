#include <gtest/gtest.h>

#include "truecut/rt/ini.hpp"

using truecut::rt::hal::Ini;
using truecut::rt::hal::IniError;

TEST(Ini, SectionsKeysCommentsAndFirstValueWins) {
  Ini ini = Ini::parse(
      "# comment\n; also a comment\n[EMCMOT]\nSERVO_PERIOD = 1000000\n"
      "  [AXIS_X]  \nMAX_VELOCITY=  25.5 \nMAX_VELOCITY = 99\n",
      "m.ini");
  EXPECT_EQ("1000000", ini.find("EMCMOT", "SERVO_PERIOD").value());
  EXPECT_EQ("25.5", ini.find("AXIS_X", "MAX_VELOCITY").value());
  EXPECT_FALSE(ini.find("AXIS_X", "SERVO_PERIOD").has_value());
  EXPECT_FALSE(ini.find("NOPE", "X").has_value());
}

TEST(Ini, MalformedLinesNameFileAndLine) {
  auto err = [](const std::string& text) {
    try {
      Ini::parse(text, "m.ini");
    } catch (const IniError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ("m.ini:2: expected KEY = VALUE, got 'JUSTAWORD'", err("[A]\nJUSTAWORD\n"));
  EXPECT_EQ("m.ini:1: KEY = VALUE before any [SECTION]", err("K = V\n"));
  EXPECT_EQ("m.ini:3: section header without ']'", err("[A]\nK=1\n[B\n"));
  EXPECT_THROW(Ini::load("/nonexistent/x.ini"), IniError);
}

// Issue 23: "RADIUS = 5<NUL>0" ran a 5 mm circle (values are handed on as C
// text, which ends at the NUL); the .hal reader already refused NUL bytes.
TEST(Ini, ANulByteIsRefusedAtItsLine) {
  const std::string text = std::string("[DEMO]\nNAME = circle\nRADIUS = 5") + '\0' + "0\n";
  try {
    Ini::parse(text, "circle.ini");
    FAIL() << "a NUL byte was read";
  } catch (const IniError& e) {
    EXPECT_EQ("circle.ini:3: not a text file (a NUL byte at column 11)", std::string(e.what()));
  }
  // In a comment too: the file is not text.
  EXPECT_THROW(Ini::parse(std::string("# a") + '\0' + "\n[A]\nK = 1\n", "c.ini"), IniError);
}
