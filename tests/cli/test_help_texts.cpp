// Every command's --help as a user reads it: it exits 0, starts with its
// usage line, and every `truecut <name>` it cites is a command that exists
// (issue 23: `diagnose --help` cited a `truecut measure` that never was),
// and its words are words (issue 23: "parameterswith").
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <regex>
#include <set>
#include <string>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;

namespace {

ProcessResult run_truecut(std::vector<std::string> args) {
  args.insert(args.begin(), cli_path().string());
  return run_process(args);
}

// The commands `truecut --help` lists: the lines "  <name>  <what>" after
// "commands:".
std::set<std::string> listed_commands() {
  const ProcessResult help = run_truecut({"--help"});
  EXPECT_EQ(0, help.exit_code);
  std::set<std::string> names;
  const auto at = help.out.find("commands:");
  EXPECT_NE(std::string::npos, at) << help.out;
  const std::regex line(R"(\n  ([a-z0-9]+) {2,}\S)");
  const std::string rest = help.out.substr(at);
  for (std::sregex_iterator it(rest.begin(), rest.end(), line), end; it != end; ++it)
    names.insert((*it)[1]);
  return names;
}

}  // namespace

TEST(HelpTexts, EveryCommandHasHelpCitingOnlyRealCommands) {
  const std::set<std::string> commands = listed_commands();
  // What the README and docs/architecture.md list.
  for (const char* expected :
       {"demo", "part", "run", "canon", "scan", "cmm", "field", "rewrite", "diagnose", "iso230"})
    EXPECT_TRUE(commands.count(expected)) << expected << " is not listed by truecut --help";
  // Cited as code (`truecut scan ...`) or as a usage line ("usage: truecut
  // run ...", continued "       truecut run ..."); prose ("a truecut
  // command", "the truecut binary") is not a citation.
  const std::regex cited(R"((?:`|usage: |\n {7})truecut ([a-z][a-z0-9]*))");
  for (const std::string& name : commands) {
    const ProcessResult help = run_truecut({name, "--help"});
    EXPECT_EQ(0, help.exit_code) << name;
    EXPECT_NE(std::string::npos, help.out.find("usage: truecut " + name)) << help.out;
    EXPECT_TRUE(help.err.empty()) << name << ": " << help.err;
    for (std::sregex_iterator it(help.out.begin(), help.out.end(), cited), end; it != end; ++it)
      EXPECT_TRUE(commands.count((*it)[1])) << "`truecut " << name << " --help` cites `truecut "
                                            << (*it)[1] << "`, which is not a command";
  }
}

// Two words glued where a string literal ended ("parameters" "with") make
// a word the documentation never uses: every word of five letters or more
// of every --help must be one docs/ or the README uses, or one of the few
// ordinary words below that they happen not to.
TEST(HelpTexts, EveryWordOfTheHelpTextsIsAWord) {
  const auto lower_words = [](const std::string& text, std::size_t min_length) {
    std::set<std::string> words;
    std::string w;
    for (const char c : text + " ") {
      if (std::isalpha(static_cast<unsigned char>(c))) {
        w += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      } else {
        if (w.size() >= min_length) words.insert(w);
        w.clear();
      }
    }
    return words;
  };
  std::string docs = read_file(source_dir() / "README.md");
  for (const auto& entry : std::filesystem::directory_iterator(source_dir() / "docs"))
    if (entry.path().extension() == ".md") docs += read_file(entry.path());
  std::set<std::string> known = lower_words(docs, 1);
  for (const char* w : {"append", "arises", "devices", "dialect", "dropping", "jumping", "locates",
                        "mirrors", "resist", "substitution"})
    known.insert(w);
  for (const std::string& name : listed_commands()) {
    const ProcessResult help = run_truecut({name, "--help"});
    for (const std::string& w : lower_words(help.out, 5))
      EXPECT_TRUE(known.count(w)) << "`truecut " << name << " --help`: \"" << w
                                  << "\" is not a word the docs use (two words glued?)";
  }
}
