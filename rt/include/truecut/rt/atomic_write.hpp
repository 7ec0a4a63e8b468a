// Writing files so that a reader never sees half of one: the bytes go to
// NAME.tmp (fsync'ed), which is then renamed over NAME. A NAME that exists
// and is not a regular file (a device such as /dev/null, a FIFO, a folder) is
// never replaced: the write is refused before anything is created. On any
// failure the .tmp file is removed and NAME is as it was.
//
//   write_file_atomically("out/run.ini", text);
//
//   StagedFiles files({dir / "a.tcf", dir / "b.csv"}, ".new");  // several, all or nothing
//   write_a(files.staged(0));          // any writer that takes a path
//   files.write(1, csv_text);          // or bytes
//   files.commit();                    // renamed only now; not committed: removed
//
//   write_files_atomically({{dir / "a.json", json}, {dir / "a.html", html}});
//
//   AtomicFileWriter out("scan.ply");  // one file written in pieces (a large mesh)
//   out.write(header); out.write(chunk); ...
//   out.commit();                      // not committed: scan.ply.tmp removed
//
// Not for servo-cycle code (allocates, does I/O, throws).
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "truecut/rt/interrupt_cleanup.hpp"

namespace truecut::rt {

// what(): "PATH: why" (PATH the file the caller asked for, or its .tmp).
class FileWriteError : public std::runtime_error {
 public:
  FileWriteError(const std::filesystem::path& path, const std::string& why);
  const std::filesystem::path& path() const { return path_; }
  const std::string& why() const { return why_; }

 private:
  std::filesystem::path path_;
  std::string why_;
};

// Throws FileWriteError "PATH exists and is not a regular file; not replaced"
// when PATH (followed if a symbolic link) exists and is not a regular file.
void require_replaceable(const std::filesystem::path& path);

// PATH.tmp written, synced and renamed over PATH. Throws FileWriteError.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

// One file written in pieces, for outputs too large to hold as one string:
// the constructor refuses a PATH that is not replaceable and creates PATH.tmp
// (a regular file, never through a symbolic link); write() appends;
// commit() syncs it and renames it over PATH. Destroyed without commit (an
// exception on the way), PATH.tmp is removed and PATH is as it was; so it is
// when the process is interrupted (interrupt_cleanup.hpp). Each
// write() is one system call or more: callers batch small pieces.
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::filesystem::path path);  // throws FileWriteError
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  const std::filesystem::path& path() const { return path_; }
  const std::filesystem::path& tmp_path() const { return tmp_path_; }
  void write(std::string_view bytes);  // throws FileWriteError
  void commit();                       // throws FileWriteError

 private:
  std::filesystem::path path_, tmp_path_;
  PendingFile pending_{tmp_path_};
  int fd_ = -1;
  bool committed_ = false;
};

// The bytes of `from` written atomically to `to`.
void copy_file_atomically(const std::filesystem::path& from, const std::filesystem::path& to);

// Several files replaced together: each is first written to TARGET+suffix;
// commit() renames them in order once all are written. Without commit (an
// exception on the way) the destructor removes the staged files and no
// target has changed (nor after SIGINT or SIGTERM, when main() installed
// remove_pending_files_on_signals()). The renames are not one atomic step: if one of them
// fails (rare: same folder, same file system), the earlier ones stay done.
class StagedFiles {
 public:
  // Refuses (FileWriteError, nothing created) when a target is not replaceable.
  explicit StagedFiles(std::vector<std::filesystem::path> targets, std::string suffix = ".tmp");
  ~StagedFiles();
  StagedFiles(const StagedFiles&) = delete;
  StagedFiles& operator=(const StagedFiles&) = delete;

  std::size_t size() const { return targets_.size(); }
  const std::filesystem::path& target(std::size_t i) const { return targets_.at(i); }
  std::filesystem::path staged(std::size_t i) const;
  // Writes and syncs staged(i).
  void write(std::size_t i, std::string_view bytes);
  // Renames every staged file over its target. Throws FileWriteError naming
  // a staged file that is missing or cannot be renamed.
  void commit();

 private:
  std::vector<std::filesystem::path> targets_;
  std::string suffix_;
  std::vector<std::unique_ptr<PendingFile>> pending_;
  bool committed_ = false;
};

// Several files from bytes, all or nothing: StagedFiles with ".tmp", each
// written, then committed. Throws FileWriteError; on failure no target has
// changed and no .tmp file is left.
void write_files_atomically(
    const std::vector<std::pair<std::filesystem::path, std::string>>& files);

}  // namespace truecut::rt
