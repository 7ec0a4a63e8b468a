// rs274_compare RS274_LISTING TRUECUT_LISTING: the oracle's call-by-call
// comparison (rs274_compare.hpp) as a command, for
// tools/linuxcnc-regression.sh. Exit 0 when the listings agree, 1 with the
// first difference on stdout, 2 when a file cannot be read.
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "rs274_compare.hpp"

namespace {

bool read_all(const char* path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  out = s.str();
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: rs274_compare RS274_LISTING TRUECUT_LISTING\n");
    return 2;
  }
  std::string expected, actual;
  for (int i : {1, 2}) {
    if (!read_all(argv[i], i == 1 ? expected : actual)) {
      std::fprintf(stderr, "rs274_compare: cannot read %s\n", argv[i]);
      return 2;
    }
  }
  using truecut::interp::testing::compare_listings;
  using truecut::interp::testing::parse_listing;
  const auto difference = compare_listings(parse_listing(expected), parse_listing(actual));
  if (!difference) return 0;
  std::printf("%s\n", difference->c_str());
  return 1;
}
