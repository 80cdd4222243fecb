// Temporary names of atomic writes (core/io/atomic_file.h), which `aperture batch --resume`
// relies on to sweep those of dead processes: one definition, parsed back to its parts, and
// names that are not temporaries refused; and the writes themselves: a missing directory, a
// throwing writer and a full disk leave the previous file as it was and no temporary behind.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "core/exr/exr.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"
#include "tests/exr_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

namespace fs = std::filesystem;
using test::listDir;
using test::patterned;
using test::readBytes;

TEST(ResumeIo, TemporaryNamesParseBackToTheirParts) {
  const std::string pid = std::to_string(::getpid());
  for (const std::string& suffix : {std::string(), std::string(".png")}) {
    for (const std::string& name : {std::string("out.exr"), std::string("a.tmp-1-2.exr")}) {
      const std::string tmp = temporaryPathFor("/d/" + name, suffix);
      ASSERT_EQ(tmp.rfind("/d/.", 0), 0u) << tmp;
      const auto parsed = parseTemporaryName(tmp.substr(3));
      ASSERT_TRUE(parsed.has_value()) << tmp;
      EXPECT_EQ(parsed->finalName, name);
      EXPECT_EQ(std::to_string(parsed->pid), pid);
      EXPECT_EQ(parsed->suffix, suffix);
    }
  }
  const auto t = parseTemporaryName(".frame_0001.exr.tmp-4242-17");
  ASSERT_TRUE(t.has_value());
  EXPECT_EQ(t->finalName, "frame_0001.exr");
  EXPECT_EQ(t->pid, 4242);
  EXPECT_EQ(t->counter, 17u);
  EXPECT_EQ(t->suffix, "");
  // Not temporaries: no leading dot, no counter, a PID that is not a number, a suffix that
  // does not start with '.', no name, a directory part.
  for (const char* name : {"frame.exr.tmp-4242-17", ".frame.exr.tmp-4242", ".frame.exr.tmp-pid-1",
                           ".frame.exr.tmp-4242-17x", ".tmp-4242-1", "d/.f.exr.tmp-1-2",
                           ".frame.exr", ".frame.exr.tmp--1"})
    EXPECT_FALSE(parseTemporaryName(name).has_value()) << name;
}

TEST(ResumeIo, APidThatCannotBeAProcessCountsAsDead) {
  EXPECT_TRUE(processAlive(long(::getpid())));
  for (const long pid : {0L, -1L, long(INT_MAX) + 1, 1L << 40})
    EXPECT_FALSE(processAlive(pid)) << pid;
}

TEST(ResumeIo, TemporariesAreFoundOnlyForTheGivenNames) {
  const std::string dir = test::scratchDir();
  for (const char* name : {".a.exr.tmp-5-0", ".a.exr.tmp-6-1.png", ".b.exr.tmp-5-0", "a.exr"})
    test::writeFile(dir + "/" + name, "partial");
  const std::vector<TemporaryFile> found =
      findTemporaries({dir + "/a.exr"}, [](long pid) { return pid == 6; });
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].path, dir + "/.a.exr.tmp-5-0");
  EXPECT_EQ(found[0].pid, 5);
  EXPECT_FALSE(found[0].alive);
  EXPECT_EQ(found[1].path, dir + "/.a.exr.tmp-6-1.png");
  EXPECT_TRUE(found[1].alive);
}

TEST(Atomic, TemporaryPathIsAHiddenSiblingWithSuffix) {
  const std::string a = temporaryPathFor("/some/dir/out.png", ".png");
  const std::string b = temporaryPathFor("/some/dir/out.png", ".png");
  const std::string prefix = "/some/dir/.out.png.tmp-" + std::to_string(::getpid()) + "-";
  EXPECT_EQ(a.compare(0, prefix.size(), prefix), 0) << a;
  EXPECT_EQ(a.substr(a.size() - 4), ".png");
  EXPECT_NE(a, b);
  EXPECT_EQ(temporaryPathFor("bare.exr").compare(0, 14, ".bare.exr.tmp-"), 0);
}

TEST(Atomic, MissingDirectoryThrowsAndCreatesNothing) {
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/absent/out.exr";
  try {
    writeExr(path, patterned(4, 4), ExrMetadata{});
    FAIL() << "no error for a missing directory";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(dir + "/absent"), std::string::npos) << what;
  }
  EXPECT_FALSE(fs::exists(dir + "/absent"));
  EXPECT_TRUE(listDir(dir).empty());
}

TEST(Atomic, ThrowingWriterKeepsThePreviousFile) {
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/notes.txt";
  writeTextAtomically(path, "previous contents\n");
  try {
    writeAtomically(path, [](const std::string& tmp) {
      test::writeFile(tmp, "half-written");
      throw Error("simulated failure");
    });
    FAIL() << "the writer's exception was swallowed";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("simulated failure"), std::string::npos) << what;
  }
  EXPECT_EQ(readBytes(path), "previous contents\n");
  EXPECT_EQ(listDir(dir), std::vector<std::string>{"notes.txt"});

  writeTextAtomically(path, "new contents\n");
  EXPECT_EQ(readBytes(path), "new contents\n");
  EXPECT_EQ(listDir(dir), std::vector<std::string>{"notes.txt"});
}

TEST(Atomic, FullDiskKeepsThePreviousExr) {
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/frame.exr";
  writeExr(path, patterned(8, 8), ExrMetadata{});
  const std::string before = readBytes(path);
  ASSERT_FALSE(before.empty());

  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // Child: files may not grow past 64 KiB; a write beyond fails with EFBIG.
    ::close(fds[0]);
    ::alarm(60);
    ::signal(SIGXFSZ, SIG_IGN);
    rlimit limit{64 * 1024, 64 * 1024};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    std::string message = "no error";
    int code = 2;
    try {
      ExrOptions options;
      options.compression = ExrCompression::None;
      writeExr(path, patterned(256, 256), ExrMetadata{}, options);  // ~3.4 MB
    } catch (const Error& e) {
      message = e.what();
      code = 0;
    } catch (const std::exception& e) {
      message = std::string("not an aperture::Error: ") + e.what();
      code = 3;
    }
    ssize_t ignored = ::write(fds[1], message.data(), message.size());
    (void)ignored;
    ::_exit(code);
  }
  ::close(fds[1]);
  std::string message;
  char buf[512];
  ssize_t got;
  while ((got = ::read(fds[0], buf, sizeof buf)) > 0) message.append(buf, size_t(got));
  ::close(fds[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "child died, status " << status;
  EXPECT_EQ(WEXITSTATUS(status), 0) << message;
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find(std::strerror(EFBIG)), std::string::npos) << message;
  EXPECT_EQ(readBytes(path), before);
  EXPECT_EQ(listDir(dir), std::vector<std::string>{"frame.exr"});
}

}  // namespace
}  // namespace aperture
