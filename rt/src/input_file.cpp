#include "truecut/rt/input_file.hpp"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <system_error>

namespace truecut::rt {

namespace fs = std::filesystem;

std::uintmax_t max_input_bytes() {
  const char* env = std::getenv("TRUECUT_MAX_INPUT_MB");
  if (!env || !*env) return kDefaultMaxInputMb << 20;
  char* end = nullptr;
  errno = 0;
  const unsigned long long mb = std::strtoull(env, &end, 10);
  if (*end != '\0' || errno != 0 || mb == 0 || mb > (1ull << 40))
    throw std::invalid_argument(std::string("TRUECUT_MAX_INPUT_MB='") + env +
                                "' must be a whole number of MB from 1 to 2^40");
  return static_cast<std::uintmax_t>(mb) << 20;
}

void check_input_file(const fs::path& path, std::string_view what) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st))
    throw InputFileError(path, "cannot open the " + std::string(what) + ": " +
                                   (ec ? ec.message() : std::string(std::strerror(ENOENT))));
  if (fs::is_directory(st)) throw InputFileError(path, "is a folder, not a " + std::string(what));
  if (!fs::is_regular_file(st))
    throw InputFileError(path,
                         "is not a regular file (a device, pipe or socket is read without "
                         "end), not a " +
                             std::string(what));
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputFileError(path, "cannot read the file size: " + ec.message());
  const std::uintmax_t limit = max_input_bytes();
  if (size > limit)
    throw InputFileError(path, std::to_string(size >> 20) + " MB is more than the " +
                                   std::to_string(limit >> 20) + " MB an input file may have (" +
                                   std::string(what) +
                                   "; the environment variable TRUECUT_MAX_INPUT_MB raises it)");
}

std::string read_input_file(const fs::path& path, std::string_view what) {
  check_input_file(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputFileError(path,
                         "cannot open the " + std::string(what) + ": " + std::strerror(errno));
  // Sized from the file first: growing a string while reading took twice
  // the file's size for a moment.
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  std::string bytes(ec ? 0 : static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  if (in.eof()) in.clear();  // shorter than its size said: the file shrank meanwhile
  bytes.append(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputFileError(path, "cannot read the " + std::string(what));
  return bytes;
}

}  // namespace truecut::rt
