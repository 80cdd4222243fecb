// Temporary names of atomic writes (core/io/atomic_file.h), which `aperture batch --resume`
// relies on to sweep those of dead processes: one definition, parsed back to its parts, and
// names that are not temporaries refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>

#include "core/io/atomic_file.h"

namespace aperture {
namespace {

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

}  // namespace
}  // namespace aperture
