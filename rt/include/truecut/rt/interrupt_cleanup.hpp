// Temporary files that must not outlive an interrupted process. A writer
// registers its NAME.tmp while it writes it; when the process is ended by
// SIGINT, SIGTERM or SIGHUP (Ctrl-C, kill, a closed terminal), the handler
// that remove_pending_files_on_signals() installs unlinks every registered
// file and then lets the signal end the process as it would have.
//
//   rt::remove_pending_files_on_signals();  // once, in main()
//   rt::PendingFile pending(tmp_path);       // while tmp_path is being written
//
// The handler only calls unlink() and raise() (async-signal-safe). At most
// kMaxPendingFiles files of up to kMaxPendingPathBytes bytes are tracked at
// once; beyond that a file is written as before, without the guarantee.
#pragma once

#include <cstddef>
#include <filesystem>

#include "truecut/rt/hal_abi.h"

namespace truecut::rt {

inline constexpr std::size_t kMaxPendingFiles = 128;
inline constexpr std::size_t kMaxPendingPathBytes = 1024;

class PendingFile {
 public:
  explicit PendingFile(const std::filesystem::path& path) noexcept;
  ~PendingFile();  // no longer removed on a signal (renamed or removed by its writer)
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;
  bool tracked() const noexcept { return slot_ >= 0; }

 private:
  int slot_ = -1;                       // in this copy's table, or the host's handle
  const tc_hal_api_t* host_ = nullptr;  // set when the host holds the name
  tc_hal_t* host_hal_ = nullptr;
};

// A component in a shared library links its own copy of this table, which
// the host's signal handler does not see. While a PendingFilesToHost lives
// (around the writing in a component's exit or service), the PendingFiles
// made on its thread are registered with the host through the ABI
// (tc_hal_api_t::pending_file_add), when the host has that call; otherwise
// in this copy's table as before.
//
//   truecut::rt::PendingFilesToHost to_host(api, hal);
//   write_file_atomically(out / "machined.stl", ...);
class PendingFilesToHost {
 public:
  PendingFilesToHost(const tc_hal_api_t* api, tc_hal_t* hal) noexcept;
  ~PendingFilesToHost();
  PendingFilesToHost(const PendingFilesToHost&) = delete;
  PendingFilesToHost& operator=(const PendingFilesToHost&) = delete;

 private:
  const tc_hal_api_t* outer_api_;  // the enclosing guard's host, restored at the end
  tc_hal_t* outer_hal_;
};

// Installs the handlers for SIGINT, SIGTERM and SIGHUP. A handler installed
// later for one of them (truecut run's own SIGINT) takes precedence while
// it is installed.
void remove_pending_files_on_signals();

// Files registered now (for tests).
std::size_t pending_file_count() noexcept;

}  // namespace truecut::rt
