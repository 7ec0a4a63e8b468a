// Turns one source line into the form LinuxCNC's reader works on: blanks
// removed and letters lower-cased outside comments, comments kept verbatim,
// and a map from every kept character back to its source column. Sinumerik
// keywords (TRAORI, TRAFOOF, BSPLINE, CSPLINE) are taken out first because
// blank removal would glue them to the next word.
#pragma once

#include <string>
#include <vector>

namespace truecut::interp {

enum class SinumerikWord { kTraori, kTrafoof, kBspline, kCspline };

struct LexedLine {
  const std::string* file = nullptr;
  int line = 0;
  std::string text;         // normalized
  std::vector<int> column;  // 1-based source column of text[i]
  int end_column = 1;       // column just past the source line
  struct Keyword {
    SinumerikWord word;
    int column;
  };
  std::vector<Keyword> sinumerik;
};

// Throws GcodeError for an unclosed or nested comment.
LexedLine lex_line(const std::string& source, const std::string& file, int line);

}  // namespace truecut::interp
