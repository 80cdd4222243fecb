// The image codec (core/io/image_codec.h), the OpenImageIO plugin loaded on first use (linked into
// the test program of a sanitizer build): what it encodes reads back, and its comparison
// statistics match their closed forms.
#include <gtest/gtest.h>
#include <link.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/io/image_codec.h"
#include "tests/support.h"

using namespace aperture;

namespace {

TEST(ImageCodec, EncodedPngReadsBackWithItsSizeAndPixels) {
  const int w = 5, h = 3;
  std::vector<unsigned char> rgb(size_t(w * h * 3));
  for (size_t k = 0; k < rgb.size(); ++k) rgb[k] = static_cast<unsigned char>(17 * k);
  const ImageToEncode image{w, h, 3, SampleType::UInt8, rgb.data(), {}, {}};
  std::vector<unsigned char> bytes;
  std::string error;
  ASSERT_TRUE(imageCodec().encode("x.png", image, bytes, error)) << error;
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(std::string(bytes.begin() + 1, bytes.begin() + 4), "PNG");  // the PNG signature
  const std::string path = test::scratchDir() + "/x.png";
  test::writeFile(path, std::string(bytes.begin(), bytes.end()));
  ImageFileInfo info;
  std::vector<unsigned char> back;
  ASSERT_TRUE(imageCodec().read(path, SampleType::UInt8, info, &back, error)) << error;
  EXPECT_EQ(info.width, w);
  EXPECT_EQ(info.height, h);
  EXPECT_EQ(info.channels, 3);
  EXPECT_EQ(info.type, SampleType::UInt8);
  EXPECT_EQ(back, rgb);
  // Read as 16 bits, OpenImageIO scales each sample by 65535 / 255 = 257.
  std::vector<unsigned char> wide;
  ASSERT_TRUE(imageCodec().read(path, SampleType::UInt16, info, &wide, error)) << error;
  ASSERT_EQ(wide.size(), 2 * rgb.size());
  for (size_t k = 0; k < rgb.size(); ++k) {
    uint16_t v;
    std::memcpy(&v, wide.data() + 2 * k, 2);
    EXPECT_EQ(v, 257 * rgb[k]) << k;
  }
}

/// Whether a shared object whose path contains `name` is loaded in this process.
bool sharedObjectLoaded(const std::string& name) {
  struct Search {
    const std::string* name;
    bool found;
  } search{&name, false};
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* data) {
        auto* s = static_cast<Search*>(data);
        if (info->dlpi_name && std::string(info->dlpi_name).find(*s->name) != std::string::npos)
          s->found = true;
        return 0;
      },
      &search);
  return search.found;
}

TEST(ImageCodec, ACodecLinkedInIsTakenOverThePlugin) {
  // Sanitizer builds link the codec into this program (aperture_oiio_linked) and imageCodec()
  // takes it over the plugin; every other build loads the plugin. Either way, after a first
  // encode, exactly one of the two is what this process runs.
  std::vector<unsigned char> bytes;
  std::string error;
  const unsigned char pixel[3] = {1, 2, 3};
  ASSERT_TRUE(
      imageCodec().encode("x.png", {1, 1, 3, SampleType::UInt8, pixel, {}, {}}, bytes, error))
      << error;
#ifdef APERTURE_SANITIZED
  EXPECT_FALSE(sharedObjectLoaded("libaperture_oiio.so"));
  EXPECT_TRUE(sharedObjectLoaded("libOpenImageIO.so")) << "linked into the test program";
#else
  EXPECT_TRUE(sharedObjectLoaded("libaperture_oiio.so"));
#endif
}

TEST(ImageCodec, FailuresReturnAnErrorInsteadOfThrowing) {
  std::vector<unsigned char> bytes;
  std::string error;
  const unsigned char pixel[3] = {0, 0, 0};
  EXPECT_FALSE(imageCodec().encode("x.unknown-extension",
                                   {1, 1, 3, SampleType::UInt8, pixel, {}, {}}, bytes, error));
  EXPECT_NE(error.find("no image writer"), std::string::npos) << error;
  ImageFileInfo info;
  error.clear();
  EXPECT_FALSE(imageCodec().read(test::scratchDir() + "/missing.png", SampleType::UInt8, info,
                                 nullptr, error));
  EXPECT_FALSE(error.empty());
}

TEST(ImageCodec, ComparisonStatisticsAreTheClosedForms) {
  // a − b is 0 on two samples and 3 and −4 on the others: mean |d| 7/4, max 4, rms 5/2.
  const float a[4] = {1, 2, 6, 0}, b[4] = {1, 2, 3, 4};
  SampleDifference d;
  std::string error;
  ASSERT_TRUE(imageCodec().compare(2, 2, 1, a, b, d, error)) << error;
  EXPECT_DOUBLE_EQ(d.mean, 7.0 / 4.0);
  EXPECT_DOUBLE_EQ(d.max, 4.0);
  EXPECT_NEAR(d.rms, std::sqrt(25.0 / 4.0), 1e-6);
}

}  // namespace
