// glTF cameras as camera-file images (apps/services/camera_file_params.cpp, gltfCameraParams;
// their axes from cameras/files gltfCvCameraFromWorld): a camera placed by a node renders what
// the same camera given as flags renders, with the flags worked out here by hand from the
// node's translation, rotation and scale; a wrong axis convention is shown to be caught; the
// image-size rules; cameras read from glTF files written by the test writer (nested nodes,
// names, errors).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "apps/services/camera_file_params.h"
#include "cameras/files/camera_file.h"
#include "cameras/registry/resolve.h"
#include "core/util/units.h"
#include "tests/camera_support.h"
#include "tests/gltf_support.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

// ---- a node by hand: translation, rotation (unit quaternion x, y, z, w), scale ----

struct Trs {
  glm::dvec3 t{0.0};
  glm::dvec4 q{0.0, 0.0, 0.0, 1.0};
  glm::dvec3 s{1.0};
};

/// q rotating v: v + 2w (q × v) + 2 q × (q × v), with q = (x, y, z) and w its scalar.
glm::dvec3 rotatedByQuaternion(const glm::dvec4& q, const glm::dvec3& v) {
  const glm::dvec3 qv(q.x, q.y, q.z);
  const glm::dvec3 c = glm::cross(qv, v);
  return v + 2.0 * q.w * c + 2.0 * glm::cross(qv, c);
}

/// T · R · S as a glTF node's matrix (column j of R is the rotated j-th basis vector).
glm::dmat4 matrixOfTrs(const Trs& n) {
  glm::dmat4 m(1.0);
  for (int j = 0; j < 3; ++j) {
    glm::dvec3 axis(0.0);
    axis[j] = 1.0;
    m[j] = glm::dvec4(rotatedByQuaternion(n.q, axis) * n.s[j], 0.0);
  }
  m[3] = glm::dvec4(n.t, 1.0);
  return m;
}

glm::dvec4 unitQuaternion(const glm::dvec3& axis, double angle) {
  const glm::dvec3 a = glm::normalize(axis) * std::sin(0.5 * angle);
  return {a.x, a.y, a.z, std::cos(0.5 * angle)};
}

std::string numberText(double x) {
  char s[40];
  std::snprintf(s, sizeof s, "%.17g", x);
  return s;
}

std::string vec3Text(const glm::dvec3& v) {
  char s[128];
  std::snprintf(s, sizeof s, "%.17g,%.17g,%.17g", v.x, v.y, v.z);
  return s;
}

// A node a little off the z axis, turned about a skew axis and scaled unevenly (the scale must
// not change the view), looking at the spheres of the default scene.
Trs cameraNode() {
  Trs n;
  n.t = glm::dvec3(0.4, 0.3, 6.0);
  n.q = unitQuaternion({0.3, 1.0, 0.2}, 0.12);
  n.s = glm::dvec3(2.0, 0.5, 3.0);
  return n;
}

/// The camera file of one glTF camera placed by `node`, as the glTF reader makes it.
CameraFile gltfFileOf(const SceneCamera& camera) {
  CameraFile file;
  file.path = "hand.gltf";
  file.format = CameraFileFormat::Gltf;
  file.gltfCameras = {camera};
  CalibratedImage image;
  image.name = camera.name;
  image.sensor = -1;
  image.gltfCamera = 0;
  image.cvCameraFromWorld = gltfCvCameraFromWorld(camera.worldFromCamera, "hand.gltf");
  file.images = {image};
  return file;
}

CameraParams paramsOfGltf(const SceneCamera& camera, const app::GltfImageSize& size) {
  const CameraFile file = gltfFileOf(camera);
  return resolveCameraParams(app::imageParamSet(file, file.images[0], size));
}

SceneCamera perspectiveCamera(const Trs& node) {
  SceneCamera c;
  c.name = "cam";
  c.node = 3;
  c.projection = SceneCamera::Projection::Perspective;
  c.yfov = 0.6;
  c.aspectRatio = 4.0 / 3.0;
  c.znear = 0.5;
  c.zfar = 40.0;
  c.worldFromCamera = matrixOfTrs(node);
  return c;
}

/// How two renders of one view differ: pixels whose primID differs, and the largest relative
/// depth difference over the pixels both hit on the same triangle.
struct GltfViewDifference {
  size_t hits = 0, otherPrim = 0;
  double maxDepth = 0;
};
GltfViewDifference gltfViewDifference(const Framebuffer& a, const Framebuffer& b) {
  GltfViewDifference d;
  for (size_t i = 0; i < a.pixelCount(); ++i) {
    d.hits += a.primId[i] != kInvalidId;
    if (a.primId[i] != b.primId[i]) {
      ++d.otherPrim;
    } else if (a.primId[i] != kInvalidId) {
      d.maxDepth =
          std::max(d.maxDepth, double(std::abs(a.depth[i] - b.depth[i])) / double(b.depth[i]));
    }
  }
  return d;
}

/// `a` and `b` show the same picture: the same triangle in all but a few pixels (a ray through
/// a shared edge may fall either side after a last-bit difference in the frame) and depth to
/// float precision.
void expectSameView(const Framebuffer& a, const Framebuffer& b) {
  const GltfViewDifference d = gltfViewDifference(a, b);
  EXPECT_GT(d.hits, a.pixelCount() / 10) << "the view should see the spheres";
  EXPECT_LE(d.otherPrim, a.pixelCount() / 1000);
  EXPECT_LT(d.maxDepth, 1e-5);
}

size_t hitsOf(const Framebuffer& fb) { return gltfViewDifference(fb, fb).hits; }

bool viewsDiffer(const Framebuffer& a, const Framebuffer& b) {
  const GltfViewDifference d = gltfViewDifference(a, b);
  return d.otherPrim > a.pixelCount() / 10 || d.maxDepth > 1e-3;
}

const test::Loaded& spheres() {
  static const test::Loaded l = test::load("procedural:default");
  return l;
}

TEST(GltfCameraParams, PerspectiveRendersAsItsFlags) {
  const Trs node = cameraNode();
  const SceneCamera camera = perspectiveCamera(node);
  app::GltfImageSize size;
  size.height = 120;  // width from aspectRatio: 160
  const CameraParams fromFile = paramsOfGltf(camera, size);
  EXPECT_EQ(fromFile.type, "perspective");
  EXPECT_EQ(fromFile.width, 160);
  EXPECT_EQ(fromFile.height, 120);

  // By hand: the eye is the node's translation, the view its −Z and up its +Y, both rotated by
  // the quaternion (scale does not turn them).
  const glm::dvec3 eye = node.t;
  const glm::dvec3 at = eye + rotatedByQuaternion(node.q, {0.0, 0.0, -1.0});
  const glm::dvec3 up = rotatedByQuaternion(node.q, {0.0, 1.0, 0.0});
  const std::string view = "--camera perspective --size 160,120 --fov " +
                           numberText(0.6 * kDegPerRad) + " --clip 0.5,40 --eye " + vec3Text(eye) +
                           " --up " + vec3Text(up);
  const CameraParams fromFlags = test::cameraParamsFromFlags(view + " --at " + vec3Text(at));
  const Framebuffer a = test::render(*spheres().scene, fromFile);
  const Framebuffer b = test::render(*spheres().scene, fromFlags);
  expectSameView(a, b);

  // The comparison catches a wrong convention: looking down +Z, or up along −Y.
  const glm::dvec3 behind = eye - rotatedByQuaternion(node.q, {0.0, 0.0, -1.0});
  EXPECT_TRUE(viewsDiffer(
      a, test::render(*spheres().scene,
                      test::cameraParamsFromFlags(view + " --at " + vec3Text(behind)))));
  const std::string upsideDown = "--camera perspective --size 160,120 --fov " +
                                 numberText(0.6 * kDegPerRad) + " --clip 0.5,40 --eye " +
                                 vec3Text(eye) + " --up " + vec3Text(-up) + " --at " + vec3Text(at);
  EXPECT_TRUE(
      viewsDiffer(a, test::render(*spheres().scene, test::cameraParamsFromFlags(upsideDown))));
}

TEST(GltfCameraParams, ClipIsZnearZfar) {
  // A far plane in front of the spheres leaves nothing; no zfar clips nothing far.
  SceneCamera camera = perspectiveCamera(cameraNode());
  camera.zfar = 1.0;
  app::GltfImageSize size;
  size.height = 60;
  EXPECT_EQ(hitsOf(test::render(*spheres().scene, paramsOfGltf(camera, size))), 0u);
  camera.zfar.reset();
  const CameraParams infinite = paramsOfGltf(camera, size);
  ASSERT_TRUE(infinite.clip);
  EXPECT_EQ(infinite.clip->x, 0.5);
  EXPECT_GE(infinite.clip->y, 3.4e38);
  EXPECT_GT(hitsOf(test::render(*spheres().scene, infinite)), 0u);
}

TEST(GltfCameraParams, OrthographicRendersAsItsFlags) {
  const Trs node = cameraNode();
  SceneCamera camera = perspectiveCamera(node);
  camera.projection = SceneCamera::Projection::Orthographic;
  camera.xmag = 1.5;
  camera.ymag = 1.0;
  const CameraParams fromFile = paramsOfGltf(camera, {});
  EXPECT_EQ(fromFile.type, "orthographic");
  EXPECT_EQ(fromFile.height, 540);  // no size: the default height, the width from xmag / ymag
  EXPECT_EQ(fromFile.width, 810);
  app::GltfImageSize size;
  size.width = 150;
  const CameraParams small = paramsOfGltf(camera, size);
  EXPECT_EQ(small.height, 100);
  const glm::dvec3 eye = node.t;
  const glm::dvec3 at = eye + rotatedByQuaternion(node.q, {0.0, 0.0, -1.0});
  const glm::dvec3 up = rotatedByQuaternion(node.q, {0.0, 1.0, 0.0});
  const CameraParams fromFlags = test::cameraParamsFromFlags(
      "--camera orthographic --size 150,100 --viewport 3,2 --eye " + vec3Text(eye) + " --at " +
      vec3Text(at) + " --up " + vec3Text(up));
  const Framebuffer a = test::render(*spheres().scene, small);
  expectSameView(a, test::render(*spheres().scene, fromFlags));
  const CameraParams wrongUp = test::cameraParamsFromFlags(
      "--camera orthographic --size 150,100 --viewport 3,2 --eye " + vec3Text(eye) + " --at " +
      vec3Text(at) + " --up " + vec3Text(-up));
  EXPECT_TRUE(viewsDiffer(a, test::render(*spheres().scene, wrongUp)));
}

TEST(GltfCameraParams, ImageSizeRules) {
  SceneCamera camera = perspectiveCamera(Trs());
  const auto sized = [&](std::optional<int> w, std::optional<int> h) {
    app::GltfImageSize size;
    size.width = w;
    size.height = h;
    const CameraParams p = paramsOfGltf(camera, size);
    return glm::ivec2(p.width, p.height);
  };
  EXPECT_EQ(sized(640, 480), glm::ivec2(640, 480));  // both: as given
  EXPECT_EQ(sized(641, 480), glm::ivec2(641, 480));  // within a pixel of the aspect
  EXPECT_EQ(sized(100, std::nullopt), glm::ivec2(100, 75));
  EXPECT_EQ(sized(std::nullopt, 100), glm::ivec2(133, 100));  // 133.3 rounded
  EXPECT_EQ(sized(std::nullopt, std::nullopt), glm::ivec2(720, 540));
  EXPECT_ERROR_MENTIONS(sized(640, 640), "hand.gltf camera 'cam' (/nodes/3)", "640x640",
                        "aspect ratio");
  camera.aspectRatio.reset();
  EXPECT_EQ(sized(64, 64), glm::ivec2(64, 64));  // no aspectRatio: the size as given
  EXPECT_ERROR_MENTIONS(sized(64, std::nullopt), "no aspectRatio", "--size W,H");
  EXPECT_ERROR_MENTIONS(sized(std::nullopt, std::nullopt), "no aspectRatio", "--size W,H");
  // The file's values go through the schema's checks, named by the image.
  camera.yfov = kPi;
  EXPECT_ERROR_MENTIONS(sized(64, 64), "hand.gltf image 'cam'");
}

TEST(GltfCameraParams, AxesOfTheNode) {
  // W is the node's +Z, V its +Y, U its +X, e its origin; scale is removed.
  const Trs node = cameraNode();
  const glm::dmat4 cv = gltfCvCameraFromWorld(matrixOfTrs(node), "n");
  // Rows of OpenCV's rotation: x = U, y = −V, z = −W.
  const glm::dvec3 axes[3] = {rotatedByQuaternion(node.q, {1, 0, 0}),
                              -rotatedByQuaternion(node.q, {0, 1, 0}),
                              -rotatedByQuaternion(node.q, {0, 0, 1})};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(cv[c][r], axes[r][c], 1e-15) << r << c;
    EXPECT_NEAR(cv[3][r], -glm::dot(axes[r], node.t), 1e-14);
  }
  glm::dmat4 sheared = matrixOfTrs(node);
  sheared[1] += 0.1 * sheared[0];
  EXPECT_ERROR_MENTIONS(gltfCvCameraFromWorld(sheared, "scene.glb: camera 'c'"),
                        "scene.glb: camera 'c'", "not a rotation");
  glm::dmat4 mirrored = matrixOfTrs(node);
  mirrored[0] = -mirrored[0];
  EXPECT_ERROR_MENTIONS(gltfCvCameraFromWorld(mirrored, "m"), "m");
  glm::dmat4 flat = matrixOfTrs(node);
  flat[2] = glm::dvec4(0.0);
  EXPECT_ERROR_MENTIONS(gltfCvCameraFromWorld(flat, "f"), "f", "z axis");
}

// ---- cameras read from a glTF file ----

glm::dquat dquatOf(const glm::dvec4& q) { return glm::dquat(q.w, q.x, q.y, q.z); }

/// A triangle, a camera rig (node 1 "rig": translated, turned about y, scaled by 2) carrying
/// the perspective camera node 2 "cam" (its own translation and rotation), an unnamed
/// orthographic camera at the root (node 3), and node 4 "cam" again (a second camera of that
/// name, a child of node 0).
struct RigNodes {
  Trs rig, cam;
};
RigNodes rigNodes() {
  RigNodes r;
  r.rig.t = glm::dvec3(0.2, -0.1, 1.0);
  r.rig.q = unitQuaternion({0.0, 1.0, 0.0}, 0.1);
  r.rig.s = glm::dvec3(2.0);
  r.cam.t = glm::dvec3(0.05, 0.1, 2.4);
  r.cam.q = unitQuaternion({1.0, 0.4, -0.3}, -0.08);
  return r;
}

test::GltfScene rigScene() {
  const RigNodes r = rigNodes();
  test::GltfScene s;
  test::GltfPrimitive triangle;
  triangle.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  s.meshes.push_back({"tri", {triangle}});
  s.cameras.resize(2);
  s.cameras[0].yfov = 0.6;
  s.cameras[0].aspectRatio = 1.5;
  s.cameras[0].znear = 0.25;
  s.cameras[1].orthographic = true;
  s.cameras[1].xmag = 2.0;
  s.cameras[1].ymag = 1.0;
  s.cameras[1].znear = 0.01;
  s.cameras[1].zfar = 50;
  s.nodes.resize(5);
  s.nodes[0].name = "tri";
  s.nodes[0].mesh = 0;
  s.nodes[0].children = {4};
  s.nodes[1].name = "rig";
  s.nodes[1].translation = r.rig.t;
  s.nodes[1].rotation = dquatOf(r.rig.q);
  s.nodes[1].scale = r.rig.s;
  s.nodes[1].children = {2};
  s.nodes[2].name = "cam";
  s.nodes[2].camera = 0;
  s.nodes[2].translation = r.cam.t;
  s.nodes[2].rotation = dquatOf(r.cam.q);
  s.nodes[3].camera = 1;
  s.nodes[3].translation = glm::dvec3(0.0, 0.0, 8.0);
  s.nodes[4].name = "cam";
  s.nodes[4].camera = 0;
  s.nodes[4].translation = glm::dvec3(0.0, 0.0, 7.0);
  s.roots = {0, 1, 3};
  return s;
}

TEST(GltfCameraFile, NestedNodesRenderAsTheirFlags) {
  const std::string dir = test::scratchDir();
  for (const char* name : {"rig.glb", "rig.gltf"}) {
    SCOPED_TRACE(name);
    const std::string path = test::writeGltf(rigScene(), dir + "/" + name);
    const CameraFile file = readCameraFile(path);
    EXPECT_EQ(file.format, CameraFileFormat::Gltf);
    ASSERT_EQ(file.images.size(), 3u);
    // Depth first from the roots: node 4 (under node 0), node 2 (under node 1), node 3. The
    // two "cam" nodes get their node index; the unnamed one is named after it.
    EXPECT_EQ(file.images[0].name, "cam_4");
    EXPECT_EQ(file.images[1].name, "cam_2");
    EXPECT_EQ(file.images[2].name, "camera_3");

    // By hand: the rig's rotation and scale carry the camera's translation; the view turns by
    // both rotations (a uniform scale turns nothing).
    const RigNodes r = rigNodes();
    const glm::dvec3 eye = r.rig.t + rotatedByQuaternion(r.rig.q, r.rig.s * r.cam.t);
    const auto turned = [&](const glm::dvec3& v) {
      return rotatedByQuaternion(r.rig.q, rotatedByQuaternion(r.cam.q, v));
    };
    const glm::dvec3 at = eye + turned({0.0, 0.0, -1.0});
    const glm::dvec3 up = turned({0.0, 1.0, 0.0});
    // The command line's road: --cameras with --image and --size.
    const CameraParams fromFile = test::cameraParamsFromFlags(std::string("--cameras ") + path +
                                                              " --image cam_2 --size 90,60");
    EXPECT_EQ(fromFile.type, "perspective");
    ASSERT_TRUE(fromFile.clip);
    EXPECT_EQ(fromFile.clip->x, 0.25);
    const CameraParams fromFlags = test::cameraParamsFromFlags(
        "--camera perspective --size 90,60 --fov " + numberText(0.6 * kDegPerRad) +
        " --clip 0.25," + numberText(double(std::numeric_limits<float>::max())) + " --eye " +
        vec3Text(eye) + " --at " + vec3Text(at) + " --up " + vec3Text(up));
    const Framebuffer a = test::render(*spheres().scene, fromFile);
    expectSameView(a, test::render(*spheres().scene, fromFlags));
    // Looking down +Z instead is caught.
    const CameraParams backwards = test::cameraParamsFromFlags(
        "--camera perspective --size 90,60 --fov " + numberText(0.6 * kDegPerRad) + " --eye " +
        vec3Text(eye) + " --at " + vec3Text(eye - turned({0.0, 0.0, -1.0})) + " --up " +
        vec3Text(up));
    EXPECT_TRUE(viewsDiffer(a, test::render(*spheres().scene, backwards)));

    // The orthographic camera: no size given, the default height and the width of xmag / ymag.
    const ParamSet ortho = app::imageParamSet(file, file.images[2]);
    const CameraParams o = resolveCameraParams(ortho);
    EXPECT_EQ(o.type, "orthographic");
    EXPECT_EQ(glm::ivec2(o.width, o.height), glm::ivec2(1080, 540));
    ASSERT_TRUE(o.viewport);
    EXPECT_EQ(*o.viewport, glm::dvec2(4.0, 2.0));
    EXPECT_EQ(o.eye, glm::dvec3(0.0, 0.0, 8.0));
  }
}

TEST(GltfCameraFile, Refusals) {
  const std::string dir = test::scratchDir();
  test::GltfScene s = rigScene();
  s.nodes[2].camera = s.nodes[3].camera = s.nodes[4].camera = -1;
  const std::string none = test::writeGltf(s, dir + "/none.glb");
  EXPECT_ERROR_MENTIONS(readCameraFile(none), "none.glb", "no camera node");
  const std::string rig = test::writeGltf(rigScene(), dir + "/rig.glb");
  EXPECT_ERROR_MENTIONS(readCameraFile(rig, CameraFileOptions{3}), "rig.glb", "3");
  EXPECT_ERROR_MENTIONS(test::cameraParamsFromFlags("--cameras " + rig), "3 images", "--image");
  EXPECT_ERROR_MENTIONS(
      test::cameraParamsFromFlags("--cameras " + rig + " --image cam_2 --size 100,100"),
      "rig.glb camera 'cam_2' (/nodes/2)", "aspect ratio 1.5");
  // Writers refuse images without a sensor.
  EXPECT_ERROR_MENTIONS(writeColmapText(readCameraFile(rig), dir + "/sparse"), "sensor index -1");
}

}  // namespace
}  // namespace aperture
