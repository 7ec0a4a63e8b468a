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

namespace {

// Starts argv[0] in `cwd` with stdin from /dev/null, stdout into out_file and
// stderr into `err_path` (a file, created, or a terminal); `close_fd`, when
// not -1, is closed in the child.
pid_t start(const std::vector<std::string>& argv, const std::filesystem::path& cwd,
            const std::filesystem::path& out_file, const std::string& err_path, int err_flags,
            int close_fd) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err_path.c_str(), err_flags, 0644);
  if (close_fd >= 0) posix_spawn_file_actions_addclose(&fa, close_fd);
  const auto abs_cwd = std::filesystem::absolute(cwd);
  posix_spawn_file_actions_addchdir_np(&fa, abs_cwd.c_str());
  std::vector<char*> args;
  for (const auto& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid;
  const int rc = posix_spawn(&pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
  return pid;
}

int exit_code_of(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::filesystem::path io_dir() {
  auto dir = binary_dir() / "test-scratch" / "process-io";
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace

ProcessResult run_process(const std::vector<std::string>& argv, const std::filesystem::path& cwd) {
  const auto dir = io_dir();
  const auto out_file = dir / ("out." + std::to_string(getpid()));
  const auto err_file = dir / ("err." + std::to_string(getpid()));
  const pid_t pid = start(argv, cwd, out_file, err_file.string(), O_WRONLY | O_CREAT | O_TRUNC, -1);
  ProcessResult r;
  r.exit_code = exit_code_of(pid);
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
  const auto out_file = io_dir() / ("tty-out." + std::to_string(getpid()));
  pid_t pid;
  try {
    pid = start(argv, cwd, out_file, terminal, O_RDWR | O_NOCTTY, master);
  } catch (...) {
    close(master);
    throw;
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
  r.exit_code = exit_code_of(pid);
  r.out = read_file(out_file);
  std::filesystem::remove(out_file);
  return r;
}

}  // namespace truecut::test
