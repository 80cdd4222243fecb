// COLMAP models (cameras/files/colmap_file.cpp) written here with image ids out of order:
// CameraFile::imageIds lists the ids in the images' order, from text and binary alike.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "cameras/files/camera_file.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// Appends `value`'s bytes (x86-64 is little-endian, as COLMAP's binary files).
template <typename T>
void putLittleEndian(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

const char* const kCamerasText =
    "# CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]\n1 PINHOLE 64 48 50 50 32 24\n";

/// Images with ids 7, 3, 12 in that (file) order.
const std::vector<std::pair<uint32_t, std::string>>& modelImages() {
  static const std::vector<std::pair<uint32_t, std::string>> images = {
      {7, "a.png"}, {3, "b.png"}, {12, "c.png"}};
  return images;
}

TEST(PointsFileImageIds, ColmapTextAndBinaryInImageOrder) {
  const std::string dir = test::scratchDir();
  std::filesystem::create_directories(dir + "/text");
  std::filesystem::create_directories(dir + "/bin");
  std::string imagesText = "# IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME\n";
  for (const auto& [id, name] : modelImages())
    imagesText += std::to_string(id) + " 1 0 0 0 0 0 0 1 " + name + "\n\n";
  test::writeFile(dir + "/text/cameras.txt", kCamerasText);
  test::writeFile(dir + "/text/images.txt", imagesText);

  std::string camerasBin, imagesBin;
  putLittleEndian<uint64_t>(camerasBin, 1);
  putLittleEndian<uint32_t>(camerasBin, 1);
  putLittleEndian<int32_t>(camerasBin, 1);  // PINHOLE
  putLittleEndian<uint64_t>(camerasBin, 64);
  putLittleEndian<uint64_t>(camerasBin, 48);
  for (double p : {50.0, 50.0, 32.0, 24.0}) putLittleEndian<double>(camerasBin, p);
  putLittleEndian<uint64_t>(imagesBin, modelImages().size());
  for (const auto& [id, name] : modelImages()) {
    putLittleEndian<uint32_t>(imagesBin, id);
    for (double q : {1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}) putLittleEndian<double>(imagesBin, q);
    putLittleEndian<uint32_t>(imagesBin, 1);
    imagesBin += name;
    imagesBin.push_back('\0');
    putLittleEndian<uint64_t>(imagesBin, 0);
  }
  test::writeFile(dir + "/bin/cameras.bin", camerasBin);
  test::writeFile(dir + "/bin/images.bin", imagesBin);

  for (const char* model : {"/text", "/bin"}) {
    const CameraFile file = readCameraFile(dir + model);
    ASSERT_EQ(file.images.size(), 3u) << model;
    ASSERT_EQ(file.imageIds.size(), 3u) << model;
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(file.images[k].name, modelImages()[k].second) << model;
      EXPECT_EQ(file.imageIds[k], std::to_string(modelImages()[k].first)) << model;
    }
  }
}

}  // namespace
}  // namespace aperture
