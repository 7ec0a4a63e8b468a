// InterpreterOptions::on_call: the calls handed over one by one, as they are
// made, are exactly the calls a stored run returns, and nothing is stored.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "interp_test_util.hpp"
#include "test_paths.hpp"

using namespace truecut::interp;
using truecut::test::scratch_dir;

namespace {
std::string described(const CanonCall& c, const std::vector<std::string>& files) {
  return files[c.context.file] + ":" + std::to_string(c.context.line) + " tool " +
         std::to_string(c.context.tool) + " op '" + c.context.operation + "' " +
         format_rs274(c.op, FormatOptions{6});
}
}  // namespace

TEST(CanonSink, StreamedCallsAreTheStoredCallsAndNothingIsStored) {
  const auto dir = scratch_dir();
  std::ofstream(dir / "side.ngc") << "o<side> sub\n  G1 X#1 Y[#1 * 2] F500\no<side> endsub\nM2\n";
  std::ofstream(dir / "main.ngc") << "(OPERATION: roughing)\n"
                                     "T1 M6\nG0 X0 Y0 Z5\n#1=0\n"
                                     "o100 while [#1 LT 50]\n"
                                     "  o<side> call [#1]\n  G1 X[#1] Y0\n  G2 X[#1] Y0 I1 J0\n"
                                     "  #1=[#1+1]\n"
                                     "o100 endwhile\n"
                                     "M2\n";
  InterpreterOptions stored_options;
  stored_options.tools = truecut::interp::testing::sample_tools();
  const CanonProgram stored = Interpreter(stored_options).run_file(dir / "main.ngc");
  ASSERT_GT(stored.calls.size(), 100u);

  std::vector<std::string> streamed;
  InterpreterOptions streaming = stored_options;
  streaming.on_call = [&](const CanonCall& c, const std::vector<std::string>& files) {
    streamed.push_back(described(c, files));
  };
  const CanonProgram rest = Interpreter(streaming).run_file(dir / "main.ngc");
  EXPECT_TRUE(rest.calls.empty()) << "streamed calls are not stored";
  EXPECT_EQ(stored.files, rest.files);

  std::vector<std::string> expected;
  for (const CanonCall& c : stored.calls)
    expected.push_back(described(c, stored.files));
  EXPECT_EQ(expected, streamed);
}

TEST(CanonSink, AnErrorStillThrowsAfterTheCallsBeforeIt) {
  int seen = 0;
  InterpreterOptions options;
  options.on_call = [&](const CanonCall&, const std::vector<std::string>&) { ++seen; };
  EXPECT_THROW(Interpreter(options).run_text("G0 X1\nG1 X2 F100\nG2 X3 Y0\nM2\n", "bad.ngc"),
               GcodeError);
  EXPECT_GT(seen, 0) << "the calls before the error went out";
}
