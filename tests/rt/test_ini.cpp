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
