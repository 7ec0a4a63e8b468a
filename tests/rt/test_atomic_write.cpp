#include "truecut/rt/atomic_write.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "test_paths.hpp"

namespace truecut::rt {
namespace {

namespace fs = std::filesystem;
using truecut::test::read_file;
using truecut::test::scratch_dir;

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir))
    names.insert(e.path().filename().string());
  return names;
}

bool is_char_device(const fs::path& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

// Lowers the file size limit so that writes past `bytes` fail with EFBIG
// (SIGXFSZ ignored); restores both on destruction.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit lowered = saved_;
    lowered.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &lowered);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit saved_{};
  void (*old_handler_)(int) = nullptr;
};

TEST(AtomicWrite, WritesAndReplacesLeavingNoTemporary) {
  const fs::path dir = scratch_dir();
  const fs::path file = dir / "out.txt";
  write_file_atomically(file, "first\n");
  EXPECT_EQ("first\n", read_file(file));
  write_file_atomically(file, std::string("second\0bytes", 12));
  EXPECT_EQ(std::string("second\0bytes", 12), read_file(file));
  write_file_atomically(file, "");
  EXPECT_EQ("", read_file(file));
  EXPECT_EQ(std::set<std::string>{"out.txt"}, listing(dir));
}

TEST(AtomicWrite, RefusesADeviceWithoutTouchingIt) {
  ASSERT_TRUE(is_char_device("/dev/null"));
  try {
    write_file_atomically("/dev/null", "never");
    FAIL() << "wrote over /dev/null";
  } catch (const FileWriteError& e) {
    EXPECT_EQ("/dev/null: exists and is not a regular file; not replaced", std::string(e.what()));
    EXPECT_EQ(fs::path("/dev/null"), e.path());
  }
  EXPECT_TRUE(is_char_device("/dev/null"));
  EXPECT_FALSE(fs::exists("/dev/null.tmp"));
}

TEST(AtomicWrite, RefusesAFifoAndAFolder) {
  const fs::path dir = scratch_dir();
  const fs::path fifo = dir / "pipe", folder = dir / "folder";
  ASSERT_EQ(0, ::mkfifo(fifo.c_str(), 0600));
  fs::create_directory(folder);
  EXPECT_THROW(write_file_atomically(fifo, "x"), FileWriteError);
  EXPECT_THROW(write_file_atomically(folder, "x"), FileWriteError);
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_TRUE(fs::is_directory(folder));
  EXPECT_EQ((std::set<std::string>{"pipe", "folder"}), listing(dir));
}

TEST(AtomicWrite, FollowsNoSymbolicLinkAtTheTemporaryName) {
  const fs::path dir = scratch_dir();
  std::ofstream(dir / "victim") << "keep";
  fs::create_symlink(dir / "victim", dir / "out.txt.tmp");
  EXPECT_THROW(write_file_atomically(dir / "out.txt", "x"), FileWriteError);
  EXPECT_EQ("keep", read_file(dir / "victim"));
  EXPECT_FALSE(fs::exists(dir / "out.txt"));
}

TEST(AtomicWrite, FailedWriteLeavesTheOldFileAndNoTemporary) {
  const fs::path dir = scratch_dir();
  const fs::path file = dir / "out.txt";
  write_file_atomically(file, "old");
  try {
    const FileSizeLimit limit(8);
    write_file_atomically(file, std::string(4096, 'x'));
    FAIL() << "a write past the file size limit succeeded";
  } catch (const FileWriteError& e) {
    EXPECT_NE(std::string::npos, std::string(e.what()).find("out.txt.tmp: cannot write"))
        << e.what();
  }
  EXPECT_EQ("old", read_file(file));
  EXPECT_EQ(std::set<std::string>{"out.txt"}, listing(dir));
}

TEST(AtomicFileWriter, WritesInPiecesAndAppearsOnlyOnCommit) {
  const fs::path dir = scratch_dir();
  const fs::path file = dir / "mesh.ply";
  write_file_atomically(file, "old");
  {
    AtomicFileWriter out(file);
    EXPECT_EQ(file.string() + ".tmp", out.tmp_path().string());
    out.write("ply\n");
    out.write(std::string(3 << 20, 'v'));
    EXPECT_EQ("old", read_file(file));
    out.commit();
    EXPECT_THROW(out.write("late"), FileWriteError);
  }
  EXPECT_EQ("ply\n" + std::string(3 << 20, 'v'), read_file(file));
  {
    AtomicFileWriter out(file);  // an exception on the way: no commit
    out.write("partial");
  }
  EXPECT_EQ("ply\n" + std::string(3 << 20, 'v'), read_file(file));
  EXPECT_EQ(std::set<std::string>{"mesh.ply"}, listing(dir));
  EXPECT_THROW(AtomicFileWriter("/dev/null"), FileWriteError);
  EXPECT_TRUE(is_char_device("/dev/null"));
  try {
    AtomicFileWriter out(dir / "missing" / "m.stl");
    FAIL() << "created a file in a missing folder";
  } catch (const FileWriteError& e) {
    EXPECT_EQ(dir / "missing" / "m.stl.tmp", e.path());
    EXPECT_EQ(0u, e.why().find("cannot create: ")) << e.why();
  }
}

TEST(AtomicWrite, CopiesAFile) {
  const fs::path dir = scratch_dir();
  write_file_atomically(dir / "a", "payload");
  copy_file_atomically(dir / "a", dir / "b");
  EXPECT_EQ("payload", read_file(dir / "b"));
  EXPECT_THROW(copy_file_atomically(dir / "missing", dir / "c"), FileWriteError);
  EXPECT_EQ((std::set<std::string>{"a", "b"}), listing(dir));
}

TEST(StagedFiles, ReplacesAllOnCommit) {
  const fs::path dir = scratch_dir();
  write_file_atomically(dir / "a.txt", "old a");
  {
    StagedFiles files({dir / "a.txt", dir / "b.txt"}, ".new");
    files.write(0, "new a");
    write_file_atomically(files.staged(1), "new b");  // a writer that takes a path
    EXPECT_EQ("old a", read_file(dir / "a.txt"));
    EXPECT_FALSE(fs::exists(dir / "b.txt"));
    files.commit();
  }
  EXPECT_EQ("new a", read_file(dir / "a.txt"));
  EXPECT_EQ("new b", read_file(dir / "b.txt"));
  EXPECT_EQ((std::set<std::string>{"a.txt", "b.txt"}), listing(dir));
}

TEST(StagedFiles, WithoutCommitNothingChanges) {
  const fs::path dir = scratch_dir();
  write_file_atomically(dir / "a.txt", "old a");
  try {
    StagedFiles files({dir / "a.txt", dir / "b.txt"});
    files.write(0, "new a");
    files.write(1, "new b");
    throw std::runtime_error("a later step failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ("old a", read_file(dir / "a.txt"));
  EXPECT_EQ(std::set<std::string>{"a.txt"}, listing(dir));
}

TEST(StagedFiles, CommitNeedsEveryFileWritten) {
  const fs::path dir = scratch_dir();
  StagedFiles files({dir / "a.txt", dir / "b.txt"});
  files.write(0, "a");
  EXPECT_THROW(files.commit(), FileWriteError);
  EXPECT_FALSE(fs::exists(dir / "a.txt"));
}

TEST(StagedFiles, RefusesADeviceAmongTheTargetsBeforeWritingAny) {
  const fs::path dir = scratch_dir();
  try {
    StagedFiles files({dir / "a.txt", "/dev/null"});
    FAIL() << "accepted /dev/null";
  } catch (const FileWriteError& e) {
    EXPECT_EQ(fs::path("/dev/null"), e.path());
  }
  EXPECT_TRUE(is_char_device("/dev/null"));
  EXPECT_TRUE(listing(dir).empty());
}

TEST(WriteFilesAtomically, WritesAllTogether) {
  const fs::path dir = scratch_dir();
  write_file_atomically(dir / "a.json", "old a");
  write_files_atomically({{dir / "a.json", "new a"}, {dir / "b.html", "new b"}});
  EXPECT_EQ("new a", read_file(dir / "a.json"));
  EXPECT_EQ("new b", read_file(dir / "b.html"));
  EXPECT_EQ((std::set<std::string>{"a.json", "b.html"}), listing(dir));
}

// One of several files fails (the second, past the file size limit): the
// first target keeps its old bytes, the second does not appear, and no
// temporary is left.
TEST(WriteFilesAtomically, OneFailingFileLeavesNoPartialOutput) {
  const fs::path dir = scratch_dir();
  write_file_atomically(dir / "a.json", "old a");
  try {
    const FileSizeLimit limit(8);
    write_files_atomically({{dir / "a.json", "new"}, {dir / "b.html", std::string(4096, 'x')}});
    FAIL() << "a write past the file size limit succeeded";
  } catch (const FileWriteError& e) {
    EXPECT_NE(std::string::npos, std::string(e.what()).find("b.html.tmp: cannot write"))
        << e.what();
  }
  EXPECT_EQ("old a", read_file(dir / "a.json"));
  EXPECT_EQ(std::set<std::string>{"a.json"}, listing(dir));
}

TEST(WriteFilesAtomically, RefusesANonRegularTargetBeforeWritingAny) {
  const fs::path dir = scratch_dir();
  fs::create_directory(dir / "b.html");
  try {
    write_files_atomically({{dir / "a.json", "a"}, {dir / "b.html", "b"}});
    FAIL() << "replaced a folder";
  } catch (const FileWriteError& e) {
    EXPECT_EQ((dir / "b.html").string() + ": exists and is not a regular file; not replaced",
              std::string(e.what()));
  }
  EXPECT_TRUE(fs::is_directory(dir / "b.html"));
  EXPECT_EQ(std::set<std::string>{"b.html"}, listing(dir));
}

}  // namespace
}  // namespace truecut::rt
