#include "truecut/rt/hal_file.hpp"

#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <vector>

#include "text_util.hpp"
#include "truecut/rt/input_file.hpp"

namespace truecut::rt::hal {

HalFileError::HalFileError(const std::string& file, int line, const std::string& message)
    : std::runtime_error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " +
                         message),
      file_(file),
      line_(line),
      message_(message) {}

namespace {

struct Context {
  Hal& hal;
  const Ini* ini;
  std::string file;
  std::filesystem::path base_dir;
  int depth;
};

void load_text(Context& ctx, const std::string& text);

// Splits one logical line into words: whitespace separates, "..." groups,
// '#' at the start of a word ends the line.
std::vector<std::string> tokenize(const std::string& line,
                                  const std::function<void(std::string)>& fail) {
  std::vector<std::string> words;
  std::string cur;
  bool in_word = false, quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    char c = line[i];
    if (quoted) {
      if (c == '"')
        quoted = false;
      else
        cur += c;
      continue;
    }
    if (c == '"') {
      quoted = in_word = true;
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') {
      if (in_word) words.push_back(cur);
      cur.clear();
      in_word = false;
      continue;
    }
    if (c == '#' && !in_word) break;
    cur += c;
    in_word = true;
  }
  if (quoted) fail("unterminated \" quote");
  if (in_word) words.push_back(cur);
  return words;
}

std::string substitute_ini(const Context& ctx, const std::string& word,
                           const std::function<void(std::string)>& fail) {
  static const std::regex ref(R"(\[([A-Za-z0-9_]+)\]([A-Za-z0-9_]+))");
  std::string out;
  auto begin = word.cbegin();
  std::smatch m;
  while (std::regex_search(begin, word.cend(), m, ref)) {
    out.append(begin, m[0].first);
    if (!ctx.ini) fail("'" + m[0].str() + "' needs an INI file (truecut run --ini FILE)");
    auto v = ctx.ini->find(m[1].str(), m[2].str());
    if (!v) fail("INI variable " + m[0].str() + " not found in " + ctx.ini->file_name());
    out += *v;
    begin = m[0].second;
  }
  out.append(begin, word.cend());
  return out;
}

int parse_int(const std::string& text, const std::string& what,
              const std::function<void(std::string)>& fail) {
  try {
    return parse_value(Type::kS32, text).s;
  } catch (const HalError&) {
    fail(what + " '" + text + "' is not an integer");
  }
  return 0;
}

bool is_arrow(const std::string& w) {
  return w == "=>" || w == "<=" || w == "<=>";
}

void run_command(Context& ctx, std::vector<std::string> w,
                 const std::function<void(std::string)>& fail) {
  Hal& hal = ctx.hal;
  const std::string cmd = w[0];
  auto need = [&](size_t min, size_t max, const char* usage) {
    if (w.size() < min || w.size() > max) fail(std::string("usage: ") + usage);
  };
  if (w.size() == 3 && w[1] == "=") {
    hal.set_pin_or_param(w[0], w[2]);
  } else if (cmd == "loadrt") {
    need(2, 1000, "loadrt MODULE [key=value ...]");
    for (size_t i = 2; i < w.size(); ++i)
      if (w[i].find('=') == std::string::npos)
        fail("loadrt " + w[1] + ": argument '" + w[i] + "' is not key=value");
    hal.load(w[1], std::vector<std::string>(w.begin() + 2, w.end()));
  } else if (cmd == "newthread") {
    need(3, 4, "newthread NAME PERIOD_NS [fp|nofp]");
    bool fp = true;
    if (w.size() == 4) {
      if (w[3] != "fp" && w[3] != "nofp")
        fail("newthread: expected fp or nofp, got '" + w[3] + "'");
      fp = w[3] == "fp";
    }
    hal.new_thread(w[1], parse_int(w[2], "period", fail), fp);
  } else if (cmd == "addf") {
    need(3, 4, "addf FUNCT THREAD [POSITION]");
    hal.add_function(w[1], w[2], w.size() == 4 ? parse_int(w[3], "position", fail) : -1);
  } else if (cmd == "net") {
    need(3, 1000, "net SIGNAL PIN [=> PIN ...]");
    const std::string& sig = w[1];
    if (hal.has_pin(sig)) fail("net: signal name '" + sig + "' is the name of a pin");
    for (size_t i = 2; i < w.size(); ++i) {
      if (is_arrow(w[i])) continue;
      if (hal.has_signal(w[i]))
        fail("net: '" + w[i] + "' is a signal; a net names one signal followed by pins");
      hal.link(w[i], sig);
    }
  } else if (cmd == "newsig") {
    need(3, 3, "newsig SIGNAL bit|float|s32|u32");
    static const std::pair<const char*, Type> types[] = {
        {"bit", Type::kBit}, {"float", Type::kFloat}, {"s32", Type::kS32}, {"u32", Type::kU32}};
    for (auto [name, t] : types)
      if (w[2] == name) return hal.new_signal(w[1], t);
    fail("newsig: unknown type '" + w[2] + "' (bit, float, s32, u32)");
  } else if (cmd == "linkps") {
    if (w.size() == 4 && is_arrow(w[2])) w.erase(w.begin() + 2);
    need(3, 3, "linkps PIN SIGNAL");
    hal.link(w[1], w[2]);
  } else if (cmd == "linksp") {
    if (w.size() == 4 && is_arrow(w[2])) w.erase(w.begin() + 2);
    need(3, 3, "linksp SIGNAL PIN");
    hal.link(w[2], w[1]);
  } else if (cmd == "unlinkp") {
    need(2, 2, "unlinkp PIN");
    hal.unlink(w[1]);
  } else if (cmd == "setp") {
    need(3, 3, "setp NAME VALUE");
    hal.set_pin_or_param(w[1], w[2]);
  } else if (cmd == "sets") {
    need(3, 3, "sets SIGNAL VALUE");
    hal.set_signal(w[1], w[2]);
  } else if (cmd == "source") {
    need(2, 2, "source FILE");
    if (ctx.depth > 16) fail("source: nested more than 16 deep");
    std::filesystem::path p = w[1];
    if (p.is_relative()) p = ctx.base_dir / p;
    std::string text;
    try {
      text = read_input_file(p, ".hal file");
    } catch (const InputFileError& e) {
      fail("source: '" + p.string() + "' " + e.reason());
    }
    Context inner{hal, ctx.ini, p.string(), p.parent_path(), ctx.depth + 1};
    load_text(inner, text);
  } else if (cmd == "start" || cmd == "stop") {
    // Threads start when `truecut run` executes them.
  } else if (cmd == "loadusr") {
    fail("loadusr is not supported: truecut runs no user-space programs from a .hal file");
  } else {
    fail("unknown command '" + cmd + "'");
  }
}

void load_text(Context& ctx, const std::string& text) {
  std::istringstream in(text);
  std::string raw, logical;
  int line_no = 0, start_line = 0;
  while (std::getline(in, raw)) {
    ++line_no;
    if (!raw.empty() && raw.back() == '\r') raw.pop_back();
    if (logical.empty()) start_line = line_no;
    if (!raw.empty() && raw.back() == '\\') {
      logical += raw.substr(0, raw.size() - 1) + " ";
      continue;
    }
    logical += raw;
    auto fail = [&](const std::string& msg) { throw HalFileError(ctx.file, start_line, msg); };
    std::vector<std::string> words = tokenize(logical, fail);
    logical.clear();
    if (words.empty()) continue;
    for (auto& word : words)
      word = substitute_ini(ctx, word, fail);
    try {
      run_command(ctx, words, fail);
    } catch (const HalFileError&) {
      throw;
    } catch (const std::exception& e) {
      fail(e.what());
    }
  }
  if (!logical.empty())
    throw HalFileError(ctx.file, start_line, "file ends after a '\\' continuation");
}

}  // namespace

void load_hal_text(Hal& hal, const std::string& text, const std::string& file_name, const Ini* ini,
                   const std::filesystem::path& base_dir) {
  Context ctx{hal, ini, file_name, base_dir, 0};
  load_text(ctx, text);
}

void load_hal_file(Hal& hal, const std::filesystem::path& file, const Ini* ini) {
  std::string text;
  try {
    text = read_input_file(file, ".hal file");
  } catch (const InputFileError& e) {
    throw HalFileError(file.string(), 0, e.reason());
  }
  if (text.find('\0') != std::string::npos)
    throw HalFileError(file.string(), 0, "not a text file (contains NUL bytes)");
  load_hal_text(hal, text, file.string(), ini, file.parent_path());
}

}  // namespace truecut::rt::hal
