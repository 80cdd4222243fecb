// The files of one view (writeViewOutputs, apps/services/view.h): the preview is written before
// the EXR, so a preview that fails leaves no EXR, and an EXR that fails leaves its preview.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "apps/services/view.h"
#include "core/exr/exr.h"
#include "tests/support.h"

namespace aperture::app {
namespace {

namespace fs = std::filesystem;
using test::errorOf;

/// Every file under `dir`, recursively (relative names).
std::vector<std::string> filesIn(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (!e.is_directory()) names.push_back(fs::relative(e.path(), dir).string());
  return names;
}

RenderedView smallView(AovMask aovs) {
  RenderedView view;
  view.fb = Framebuffer(4, 3, aovs);
  view.camera.width = 4;
  view.camera.height = 3;
  return view;
}

TEST(Outputs, APreviewThatFailsToWriteLeavesNoExr) {
  const std::string dir = test::scratchDir();
  test::writeFile(dir + "/afile", "a regular file");
  const std::string exr = dir + "/x.exr";
  const RenderedView view = smallView(kAovColor | kAovDepth);
  const RenderedView unpreviewable = smallView(kAovPosition);
  struct Case {
    const char* what;
    const RenderedView& view;
    std::string preview;
  } cases[] = {
      {"the preview's directory cannot be created", view, dir + "/afile/p.png"},
      {"no writer for the extension", view, dir + "/p.xyz"},
      {"no AOV to preview", unpreviewable, dir + "/p.png"},
  };
  for (const Case& c : cases) {
    const std::string message =
        errorOf([&] { writeViewOutputs(c.view, ExrMetadata{}, ExrOptions{}, exr, c.preview); });
    EXPECT_NE(message.find(c.preview), std::string::npos) << c.what << ": " << message;
    EXPECT_FALSE(fs::exists(exr)) << c.what << ": an EXR was written although its preview failed";
    EXPECT_EQ(filesIn(dir), std::vector<std::string>{"afile"}) << c.what;
  }
  // Both written; then an EXR that fails leaves its preview (written first) and no EXR.
  ASSERT_EQ(errorOf([&] { writeViewOutputs(view, {}, {}, exr, dir + "/p.png"); }), "");
  EXPECT_TRUE(isCompleteExr(exr));
  EXPECT_TRUE(fs::exists(dir + "/p.png"));
  const std::string message =
      errorOf([&] { writeViewOutputs(view, {}, {}, dir + "/afile/y.exr", dir + "/q.png"); });
  EXPECT_NE(message.find("afile"), std::string::npos) << message;
  EXPECT_TRUE(fs::exists(dir + "/q.png"));
}

}  // namespace
}  // namespace aperture::app
