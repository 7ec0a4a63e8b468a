// The .hal reader: commands, INI substitution, and errors naming file:line.
#include <gtest/gtest.h>

#include <fstream>

#include "test_paths.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut::rt::hal;

namespace {

HalOptions with_test_components() {
  HalOptions o;
  o.component_path = {truecut::test::test_component_dir(), truecut::test::component_dir()};
  o.output_dir = truecut::test::scratch_dir();
  return o;
}

// Loads `text` and returns the error message ("" when it loads).
std::string load_error(const std::string& text, const Ini* ini = nullptr) {
  Hal hal(with_test_components());
  try {
    load_hal_text(hal, text, "cfg.hal", ini);
  } catch (const HalFileError& e) {
    return e.what();
  }
  return "";
}

const char* kBase =
    "loadrt threads name1=servo-thread period1=1000000\n"
    "loadrt siggen\n"
    "loadrt test_counter count=2\n";

}  // namespace

TEST(HalFile, WiresComponentsAndThreads) {
  Hal hal(with_test_components());
  load_hal_text(hal,
                std::string(kBase) +
                    "# a comment line\n"
                    "net wave siggen.0.sine => test_counter.0.in   # trailing comment\n"
                    "setp siggen.0.frequency 2.5\n"
                    "test_counter.1.step = 3\n"
                    "newsig spare float\n"
                    "sets spare 1.5\n"
                    "addf siggen.0.update servo-thread\n"
                    "addf test_counter.0.update servo-thread\n"
                    "addf test_counter.1.update servo-thread 1\n",
                "cfg.hal");
  EXPECT_EQ(2.5, hal.get_pin_or_param("siggen.0.frequency").f);
  EXPECT_EQ(3, hal.get_pin_or_param("test_counter.1.step").s);
  EXPECT_EQ(1.5, hal.get_signal("spare").f);
  auto threads = hal.threads();
  ASSERT_EQ(1u, threads.size());
  EXPECT_EQ(1000000, threads[0].period_ns);
  EXPECT_EQ((std::vector<std::string>{"test_counter.1.update", "siggen.0.update",
                                      "test_counter.0.update"}),
            threads[0].functions);
}

TEST(HalFile, NewthreadAndPositionsCountFromTheEnd) {
  Hal hal(with_test_components());
  load_hal_text(hal,
                "newthread fast 125000 fp\n"
                "loadrt test_counter count=3\n"
                "addf test_counter.0.update fast\n"
                "addf test_counter.1.update fast -2\n"  // before the last one
                "addf test_counter.2.update fast 1\n",
                "cfg.hal");
  EXPECT_EQ((std::vector<std::string>{"test_counter.2.update", "test_counter.1.update",
                                      "test_counter.0.update"}),
            hal.threads()[0].functions);
}

TEST(HalFile, IniSubstitutionAnywhereInAWord) {
  Ini ini = Ini::parse("[EMCMOT]\nSERVO_PERIOD = 250000\n[X]\nNAME = fast\n", "m.ini");
  Hal hal(with_test_components());
  load_hal_text(hal, "loadrt threads name1=[X]NAME period1=[EMCMOT]SERVO_PERIOD\n", "cfg.hal",
                &ini);
  ASSERT_TRUE(hal.has_thread("fast"));
  EXPECT_EQ(250000, hal.threads()[0].period_ns);
}

TEST(HalFile, LineContinuationAndQuotes) {
  Hal hal(with_test_components());
  load_hal_text(hal,
                "loadrt threads \\\n  name1=t period1=1000000\n"
                "loadrt siggen names=\"a\"\n",
                "cfg.hal");
  EXPECT_TRUE(hal.has_thread("t"));
  EXPECT_TRUE(hal.has_pin("a.sine"));
}

TEST(HalFile, ErrorsNameFileLineAndProblem) {
  const std::string base = kBase;  // lines 1-3
  EXPECT_EQ("cfg.hal:4: pin 'siggen.0.nope' does not exist",
            load_error(base + "net s siggen.0.nope\n"));
  EXPECT_EQ("cfg.hal:5: type mismatch: pin 'siggen.0.clock' is bit, signal 's' is float",
            load_error(base + "net s siggen.0.sine\nnet s siggen.0.clock\n"));
  EXPECT_EQ(
      "cfg.hal:5: signal 's' already has a writer (siggen.0.sine); pin 'siggen.0.cosine' "
      "cannot be a second one",
      load_error(base + "net s siggen.0.sine\nnet s siggen.0.cosine\n"));
  EXPECT_EQ(
      "cfg.hal:5: pin 'test_counter.0.in' is linked to signal 's'; use sets on the signal "
      "instead",
      load_error(base + "net s test_counter.0.in\nsetp test_counter.0.in 1\n"));
  EXPECT_EQ("cfg.hal:4: unknown command 'linkk'", load_error(base + "linkk a b\n"));
  EXPECT_EQ("cfg.hal:4: thread 'nothread' not found",
            load_error(base + "addf siggen.0.update nothread\n"));
  EXPECT_EQ(
      "cfg.hal:5: function 'siggen.0.update' already added to thread 'servo-thread'",
      load_error(base + "addf siggen.0.update servo-thread\naddf siggen.0.update servo-thread\n"));
  EXPECT_EQ("cfg.hal:4: value '1.0x' is not a valid float (not a number)",
            load_error(base + "setp siggen.0.frequency 1.0x\n"));
  EXPECT_EQ("cfg.hal:4: module 'siggen' is already loaded", load_error(base + "loadrt siggen\n"));
  EXPECT_EQ("cfg.hal:1: '[A]B' needs an INI file (truecut run --ini FILE)",
            load_error("loadrt threads name1=t period1=[A]B\n"));
  Ini ini = Ini::parse("[A]\nC = 1\n", "m.ini");
  EXPECT_EQ("cfg.hal:1: INI variable [A]B not found in m.ini",
            load_error("loadrt threads name1=t period1=[A]B\n", &ini));
  EXPECT_EQ(
      "cfg.hal:4: loadusr is not supported: truecut runs no user-space programs from a "
      ".hal file",
      load_error(base + "loadusr halui\n"));
}

TEST(HalFile, UnknownComponentListsTheSearchedFolders) {
  std::string err = load_error("loadrt no_such_comp\n");
  EXPECT_NE(err.find("cfg.hal:1: no component 'no_such_comp'"), std::string::npos) << err;
  EXPECT_NE(err.find("no_such_comp.so"), std::string::npos) << err;
}

TEST(HalFile, ComponentArgumentErrorsAreReported) {
  EXPECT_EQ(
      "cfg.hal:1: loadrt siggen: initialisation failed (Invalid argument): siggen has no "
      "argument 'bogus'",
      load_error("loadrt siggen bogus=1\n"));
  EXPECT_EQ(
      "cfg.hal:1: loadrt recorder: initialisation failed (Invalid argument): file= is "
      "required (e.g. file=trace.csv)",
      load_error("loadrt recorder columns=a\n"));
}

TEST(HalFile, SourceIncludesAnotherFileWithItsOwnLineNumbers) {
  auto dir = truecut::test::scratch_dir();
  {
    std::ofstream(dir / "inner.hal") << "loadrt siggen\n\nsetp siggen.0.nothing 1\n";
    std::ofstream(dir / "outer.hal") << "# outer\nsource inner.hal\n";
  }
  Hal hal(with_test_components());
  try {
    load_hal_file(hal, dir / "outer.hal");
    FAIL();
  } catch (const HalFileError& e) {
    EXPECT_EQ((dir / "inner.hal").string(), e.file());
    EXPECT_EQ(3, e.line());
    EXPECT_EQ("no pin or parameter named 'siggen.0.nothing'", e.message());
  }
}

TEST(HalFile, MissingAndBinaryFilesAreRejected) {
  auto dir = truecut::test::scratch_dir();
  Hal hal(with_test_components());
  EXPECT_THROW(load_hal_file(hal, dir / "absent.hal"), HalFileError);
  {
    std::ofstream f(dir / "bin.hal", std::ios::binary);
    f.write("loadrt\0\1\2", 9);
  }
  try {
    load_hal_file(hal, dir / "bin.hal");
    FAIL();
  } catch (const HalFileError& e) {
    EXPECT_NE(std::string(e.what()).find("not a text file"), std::string::npos);
  }
}

TEST(HalFile, ThreadsStopAtLinuxCncsTaskLimit) {
  // Issue 23: each newthread cost 6.5 MB with no cap.
  std::string text;
  for (std::size_t i = 0; i < kMaxThreads; ++i)
    text += "newthread t" + std::to_string(i) + " 1000000\n";
  EXPECT_EQ("", load_error(text));
  EXPECT_EQ(64u, kMaxThreads);  // RTAPI_MAX_TASKS of LinuxCNC 2.9
  EXPECT_EQ(
      "cfg.hal:65: thread 't64': more than 64 threads (LinuxCNC's RTAPI has as many tasks "
      "at most)",
      load_error(text + "newthread t64 1000000\n"));
}
