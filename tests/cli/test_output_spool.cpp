// OutputSpool (cli/output_spool.hpp): output held back until a command has
// succeeded, in memory up to a limit and in a temporary file beyond it.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "output_spool.hpp"

using truecut::cli::OutputSpool;

namespace {
std::string written(OutputSpool& spool) {
  std::FILE* f = std::tmpfile();
  spool.write_to(f);
  std::rewind(f);
  std::string text;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0)
    text.append(buf, n);
  std::fclose(f);
  return text;
}
}  // namespace

TEST(OutputSpool, SmallOutputStaysInMemoryAndComesOutWhole) {
  OutputSpool spool(1024);
  spool.append("    1 N..... STRAIGHT_FEED(1.0000, 0.0000, 0.0000)\n");
  spool.append("    2 N..... PROGRAM_END()\n");
  EXPECT_FALSE(spool.spilled());
  EXPECT_EQ("    1 N..... STRAIGHT_FEED(1.0000, 0.0000, 0.0000)\n    2 N..... PROGRAM_END()\n",
            written(spool));
}

TEST(OutputSpool, LongOutputGoesThroughAFileAndComesOutInOrder) {
  OutputSpool spool(100);
  std::string expected;
  for (int i = 0; i < 5000; ++i) {
    const std::string line = std::to_string(i) + " N..... STRAIGHT_TRAVERSE()\n";
    spool.append(line);
    expected += line;
  }
  EXPECT_TRUE(spool.spilled()) << "beyond 100 bytes the text goes to the file";
  EXPECT_EQ(expected.size(), spool.size());
  EXPECT_EQ(expected, written(spool));
}

TEST(OutputSpool, NothingAppendedWritesNothing) {
  OutputSpool spool(10);
  EXPECT_EQ("", written(spool));
}
