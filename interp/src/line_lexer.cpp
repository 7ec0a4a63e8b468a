#include "line_lexer.hpp"

#include <cctype>
#include <string_view>

#include "truecut/interp/error.hpp"

namespace truecut::interp {

namespace {

struct KeywordSpelling {
  std::string_view text;
  SinumerikWord word;
};
constexpr KeywordSpelling kKeywords[] = {{"traori", SinumerikWord::kTraori},
                                         {"trafoof", SinumerikWord::kTrafoof},
                                         {"bspline", SinumerikWord::kBspline},
                                         {"cspline", SinumerikWord::kCspline}};

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

bool matches_at(const std::string& s, size_t at, std::string_view word) {
  if (at + word.size() > s.size()) return false;
  for (size_t k = 0; k < word.size(); ++k)
    if (std::tolower(static_cast<unsigned char>(s[at + k])) != word[k]) return false;
  return true;
}

// Blanks out Sinumerik keywords standing as separate tokens outside comments.
std::string take_keywords(const std::string& src, std::vector<LexedLine::Keyword>& found) {
  std::string out = src;
  bool in_comment = false;
  for (size_t i = 0; i < out.size(); ++i) {
    char c = out[i];
    if (in_comment) {
      if (c == ')') in_comment = false;
      continue;
    }
    if (c == ';') break;
    if (c == '(') {
      in_comment = true;
      continue;
    }
    if (i > 0 && !is_blank(out[i - 1]) && out[i - 1] != ')') continue;
    for (const auto& k : kKeywords) {
      if (!matches_at(out, i, k.text)) continue;
      size_t end = i + k.text.size();
      // TRAORI(1): the Sinumerik argument form; the parenthesis is not a comment.
      if (k.word == SinumerikWord::kTraori && end < out.size() && out[end] == '(') {
        size_t close = out.find(')', end);
        bool digits = close != std::string::npos;
        for (size_t j = end + 1; digits && j < close; ++j)
          digits = std::isdigit(static_cast<unsigned char>(out[j])) || is_blank(out[j]);
        if (digits) end = close + 1;
      }
      if (end < out.size() && !is_blank(out[end]) && out[end] != ';' && out[end] != '(') continue;
      found.push_back({k.word, static_cast<int>(i) + 1});
      for (size_t j = i; j < end; ++j)
        out[j] = ' ';
      i = end - 1;
      break;
    }
  }
  return out;
}

}  // namespace

LexedLine lex_line(const std::string& source, const std::string& file, int line) {
  LexedLine out;
  out.file = &file;
  out.line = line;
  out.end_column = static_cast<int>(source.size()) + 1;
  const std::string src = take_keywords(source, out.sinumerik);
  size_t comment_start = 0;
  bool in_comment = false;
  for (size_t i = 0; i < src.size(); ++i) {
    const char c = src[i];
    const int col = static_cast<int>(i) + 1;
    if (in_comment) {
      if (c == '(') throw GcodeError({file, line, col}, "nested comment: '(' inside a comment");
      out.text.push_back(c);
      out.column.push_back(col);
      if (c == ')') in_comment = false;
      continue;
    }
    if (c == '(') {
      in_comment = true;
      comment_start = i;
      out.text.push_back(c);
      out.column.push_back(col);
      continue;
    }
    if (c == ';') {  // the rest of the line is a comment, kept verbatim
      for (size_t j = i; j < src.size(); ++j) {
        out.text.push_back(src[j]);
        out.column.push_back(static_cast<int>(j) + 1);
      }
      break;
    }
    if (is_blank(c)) continue;
    out.text.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
    out.column.push_back(col);
  }
  if (in_comment)
    throw GcodeError({file, line, static_cast<int>(comment_start) + 1},
                     "unclosed comment: '(' without ')'");
  return out;
}

}  // namespace truecut::interp
