#include "run_process.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <stdexcept>

#include "test_paths.hpp"

extern char** environ;

namespace truecut::test {

ProcessResult run_process(const std::vector<std::string>& argv, const std::filesystem::path& cwd) {
  auto dir = binary_dir() / "test-scratch" / "process-io";
  std::filesystem::create_directories(dir);
  const auto out_file = dir / ("out." + std::to_string(getpid()));
  const auto err_file = dir / ("err." + std::to_string(getpid()));

  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  auto abs_cwd = std::filesystem::absolute(cwd);
  posix_spawn_file_actions_addchdir_np(&fa, abs_cwd.c_str());

  std::vector<char*> args;
  for (const auto& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid;
  int rc = posix_spawn(&pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  ProcessResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_file(out_file);
  r.err = read_file(err_file);
  std::filesystem::remove(out_file);
  std::filesystem::remove(err_file);
  return r;
}

ProcessResult run_process_on_a_terminal(const std::vector<std::string>& argv,
                                        const std::filesystem::path& cwd) {
  const int master = posix_openpt(O_RDWR | O_NOCTTY);
  if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0)
    throw std::runtime_error("cannot open a pseudo terminal");
  const std::string terminal = ptsname(master);
  auto dir = binary_dir() / "test-scratch" / "process-io";
  std::filesystem::create_directories(dir);
  const auto out_file = dir / ("tty-out." + std::to_string(getpid()));

  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, terminal.c_str(), O_RDWR | O_NOCTTY, 0);
  posix_spawn_file_actions_addclose(&fa, master);
  auto abs_cwd = std::filesystem::absolute(cwd);
  posix_spawn_file_actions_addchdir_np(&fa, abs_cwd.c_str());
  std::vector<char*> args;
  for (const auto& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid;
  const int rc = posix_spawn(&pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    close(master);
    throw std::runtime_error("cannot start " + argv[0]);
  }
  // Read while it runs (a full terminal would stop it); once every holder
  // of the terminal's other end has closed it, read fails with EIO.
  ProcessResult r;
  char buffer[4096];
  for (;;) {
    const ssize_t n = read(master, buffer, sizeof buffer);
    if (n > 0) {
      r.err.append(buffer, static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;
  }
  close(master);
  int status = 0;
  waitpid(pid, &status, 0);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_file(out_file);
  std::filesystem::remove(out_file);
  return r;
}

}  // namespace truecut::test
