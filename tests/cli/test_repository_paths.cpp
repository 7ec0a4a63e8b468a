// The clone alone passes: no tracked file may reference a path outside the
// repository — a sibling folder of the checkout, a machine's home or work
// folder, or (in CMake files) a relative path that climbs above the
// repository's root from the file's own folder. The files are those
// `git ls-files` lists in the source folder, read from the working tree.
//
// The needles below are put together from pieces so that this file does
// not trip its own check.
#include <gtest/gtest.h>

#include <cctype>
#include <cstring>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "oracle.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"

namespace truecut::test {
namespace {

namespace fs = std::filesystem;

struct Finding {
  std::string file;
  int line;
  std::string what, text;
};

// Lines split at LF, CR LF or a lone CR (a vendored data file has CR only).
std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n' || c == '\r') {
      out.push_back(cur);
      cur.clear();
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

bool is_binary(const std::string& text) {
  return text.find('\0') != std::string::npos;
}

// A character that can be part of a path component: a needle after one of
// these is inside a longer (relative) path, e.g. "$dir/root/usr".
bool path_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("_.-~$}/+@", c) != nullptr;
}

// Absolute folders of one machine or another, and the sibling data folder.
void scan_needles(const std::string& file, const std::vector<std::string>& lines,
                  std::vector<Finding>& out) {
  const std::string up = std::string("..") + "/";
  const std::string sibling = up + "shared";
  const std::vector<std::string> absolute = {"/" + std::string("work") + "/",
                                             "/" + std::string("home") + "/",
                                             "/" + std::string("root") + "/"};
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const std::string& l = lines[n];
    if (l.find(sibling) != std::string::npos)
      out.push_back({file, static_cast<int>(n + 1), "a folder beside the repository", l});
    for (const auto& a : absolute)
      for (auto at = l.find(a); at != std::string::npos; at = l.find(a, at + 1))
        if (at == 0 || !path_char(l[at - 1])) {
          out.push_back({file, static_cast<int>(n + 1), "an absolute path (" + a + ")", l});
          break;
        }
  }
}

bool is_cmake(const std::string& file) {
  const std::string name = fs::path(file).filename().string();
  return name == "CMakeLists.txt" || fs::path(file).extension() == ".cmake";
}

// In CMake files: a path that climbs above the repository's root, from the
// root (CMAKE_SOURCE_DIR, PROJECT_SOURCE_DIR) or from the file's own folder
// (CMAKE_CURRENT_SOURCE_DIR, CMAKE_CURRENT_LIST_DIR, a bare relative path).
void scan_cmake_climbs(const std::string& file, const std::vector<std::string>& lines,
                       std::vector<Finding>& out) {
  const int own_depth = static_cast<int>(
      std::distance(fs::path(file).parent_path().begin(), fs::path(file).parent_path().end()));
  static const std::regex token(R"([^\s"'()]+)");
  static const std::regex var(R"(^\$\{([A-Za-z_]+)\}(.*)$)");
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const std::string& l = lines[n];
    const std::string code = l.substr(0, l.find('#'));
    for (auto it = std::sregex_iterator(code.begin(), code.end(), token);
         it != std::sregex_iterator(); ++it) {
      std::string path = it->str();
      if (path.find("..") == std::string::npos) continue;
      int depth = own_depth;
      std::smatch m;
      if (std::regex_match(path, m, var)) {
        const std::string name = m[1];
        if (name == "CMAKE_SOURCE_DIR" || name == "PROJECT_SOURCE_DIR" ||
            name == std::string("truecut") + "_SOURCE_DIR")
          depth = 0;
        else if (name != "CMAKE_CURRENT_SOURCE_DIR" && name != "CMAKE_CURRENT_LIST_DIR")
          continue;  // the build folder or another variable: not the repository
        path = m[2];
      } else if (path.find("${") != std::string::npos || path.front() == '/') {
        continue;
      }
      bool climbs = false;
      std::stringstream parts(path);
      std::string part;
      while (std::getline(parts, part, '/')) {
        if (part == "..") {
          if (--depth < 0) climbs = true;
        } else if (!part.empty() && part != ".") {
          ++depth;
        }
      }
      if (climbs)
        out.push_back({file, static_cast<int>(n + 1), "a path above the repository's root", l});
    }
  }
}

std::vector<Finding> scan(const std::string& file, const std::string& text) {
  std::vector<Finding> out;
  const auto lines = lines_of(text);
  scan_needles(file, lines, out);
  if (is_cmake(file)) scan_cmake_climbs(file, lines, out);
  return out;
}

std::string describe(const std::vector<Finding>& findings) {
  std::string s;
  for (const auto& f : findings)
    s +=
        f.file + ":" + std::to_string(f.line) + ": " + f.what + ": " + f.text.substr(0, 200) + "\n";
  return s;
}

TEST(RepositoryPaths, TheScanFindsWhatItLooksFor) {
  const std::string up = std::string("..") + "/";
  const std::string home = "/" + std::string("home") + "/";
  const std::string src = std::string("${CMAKE_") + "SOURCE_DIR}";
  EXPECT_EQ(scan("docs/x.md", "a\nsee " + up + "shared/data/x.csv\n").at(0).line, 2);
  EXPECT_EQ(scan("docs/x.md", "cd " + home + "me/data\n").size(), 1u);
  EXPECT_EQ(scan("docs/x.md", "x=\"" + home + "me\"\n").size(), 1u);
  EXPECT_TRUE(scan("tests/x.sh", "\"$dir/" + std::string("root") + "/usr/bin\"\n").empty());
  EXPECT_TRUE(scan("docs/x.md", "build/rs274-oracle/" + std::string("root") + "/usr\n").empty());
  // CMake: from the root or from the file's own folder.
  EXPECT_EQ(scan("CMakeLists.txt", "set(D \"" + src + "/" + up + "data\")\n").size(), 1u);
  EXPECT_TRUE(scan("CMakeLists.txt", "set(D \"" + src + "/data/" + up + "x\")\n").empty());
  EXPECT_TRUE(scan("tests/CMakeLists.txt", "add_subdirectory(" + up + "cli x)\n").empty());
  EXPECT_EQ(scan("tests/CMakeLists.txt", "include(" + up + up + "x.cmake)\n").size(), 1u);
  EXPECT_EQ(scan("cmake/a.cmake", "set(X ${CMAKE_CURRENT_LIST_DIR}/" + up + up + "y)\n").at(0).file,
            "cmake/a.cmake");
  EXPECT_TRUE(scan("CMakeLists.txt", "set(X ${CMAKE_BINARY_DIR}/" + up + "y)\n").empty());
  EXPECT_TRUE(scan("CMakeLists.txt", "# " + up + up + "only a comment\n").empty());
  // Lone CR line ends count lines too.
  EXPECT_EQ(scan("data/x.csv", "a\rb\r" + up + "shared\r").at(0).line, 3);
}

TEST(RepositoryPaths, NoTrackedFileReferencesAPathOutsideTheRepository) {
  const auto git = find_on_path("git");
  if (!git) {
    TRUECUT_ORACLE_MISSING("git is not on PATH: install the Debian package git");
  }
  const ProcessResult ls =
      run_process({git->string(), "-C", source_dir().string(), "ls-files", "-z"});
  if (ls.exit_code != 0) {
    std::string err = ls.err.substr(0, 200);
    while (!err.empty() && std::isspace(static_cast<unsigned char>(err.back())))
      err.pop_back();
    TRUECUT_ORACLE_MISSING("the source folder " + source_dir().string() +
                           " is not a git checkout (git ls-files: " + err +
                           "): run the test in a clone of the repository");
  }
  std::vector<Finding> findings;
  int scanned = 0;
  std::size_t start = 0;
  for (std::size_t end; (end = ls.out.find('\0', start)) != std::string::npos; start = end + 1) {
    const std::string file = ls.out.substr(start, end - start);
    const fs::path path = source_dir() / file;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) continue;  // deleted in the working tree, or a link
    const std::string text = read_file(path);
    if (is_binary(text)) continue;
    ++scanned;
    for (auto& f : scan(file, text))
      findings.push_back(std::move(f));
  }
  EXPECT_GT(scanned, 100) << "git ls-files listed too few files:\n" << ls.out.substr(0, 500);
  EXPECT_TRUE(findings.empty())
      << "tracked files reference paths outside the repository (a clone alone would not have "
         "them):\n"
      << describe(findings);
}

}  // namespace
}  // namespace truecut::test
