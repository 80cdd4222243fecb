#pragma once
// The tiled, multithreaded frame loop: camera packets -> rtcIntersectN -> AOV framebuffers.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/aov/frame_pixels.h"
#include "core/aov/framebuffer.h"
#include "core/engine/camera.h"
#include "core/engine/scene.h"

namespace aperture {

/// The frame the normal and shading-normal AOVs are written in. World: world space. OpenCV:
/// the camera's axes x right, y down, z forward (along the view direction). OpenGL: x right,
/// y up, z backwards (the lecture's U, V, W).
enum class NormalFrame { World, OpenCV, OpenGL };
NormalFrame parseNormalFrame(const std::string& name);  ///< world|opencv|opengl, else Error
const char* normalFrameName(NormalFrame frame);
/// The rotation taking world-space directions into `frame` of the camera described by
/// `camera` (rows: OpenCV U, −V, −W; OpenGL U, V, W; World the identity). The one owner of
/// the normal frames: the frame loop applies it to normal and shading-normal.
glm::dmat3 normalFrameFromWorld(NormalFrame frame, const CameraDescription& camera);

struct RenderSettings {
  int packetWidth = 16;  ///< 1, 4, 8 or 16 rays per rtcIntersectN call (blocks 1x1, 2x2, 4x2, 4x4)
  int tileSize = 32;     ///< tile edge in pixels (a multiple of 4); tiles are the unit of TBB work
  int spp = 1;           ///< samples per pixel (must match the camera's)
  NormalFrame normalFrame = NormalFrame::World;
  /// Measurement mode (`aperture bench --null`), not for images: the frame loop runs as usual
  /// but Embree is never called. Every traced lane k "hits" with t = 1, Ng = −dir, u = v =
  /// 0.25, geomID 0, no instance and primID = k mod (object 0's triangle count), so ray
  /// generation and every requested AOV store run. Chosen once per frame; not available with
  /// layered hits or a culled scene; throws Error for a scene without objects.
  bool nullTrace = false;
  /// Resolves a ray that misses the scene's box (Scene::box, core/engine/scene_box.h) as a miss
  /// without calling Embree. Conservative: the image is bit-identical either way. Off only to
  /// measure what it saves (`aperture bench --no-scene-box`).
  bool sceneBoxTest = true;
  /// With sceneBoxTest: for a camera with a projective map from one eye (pinhole perspective,
  /// undistorted calibrated), the packets whose 4x4 block sees no occupied cell of the scene
  /// (core/engine/coverage_mask.h) are misses without calling Embree; the mask replaces the box
  /// test there. Conservative: the image is bit-identical either way. Off only to measure what it
  /// saves (`aperture bench --no-coverage-mask`).
  bool coverageMask = true;
};

struct RenderStats {
  double seconds = 0;  ///< wall time of the frame
  /// Rays with a valid lane: passed to Embree, or resolved as misses by the scene-box test or
  /// the coverage mask.
  uint64_t raysTraced = 0;
  uint64_t raysSkipped =
      0;  ///< lanes masked because the camera gave no ray or Embree cannot trace it (traceableRay)
  /// Of raysTraced, those the scene-box test or the coverage mask resolved as misses without
  /// Embree (in the null trace, those they would have resolved: every lane still fakes a hit
  /// there).
  uint64_t raysOutsideBox = 0;
  /// Fraction of the image's blocks the frame's coverage mask covered; −1 when the frame had
  /// none (RenderSettings::coverageMask).
  double maskCovered = -1;
  /// Whether the frame ran the scene-box test (RenderSettings::sceneBoxTest; not when the
  /// coverage mask replaced it, nor when every ray starts inside the box).
  bool boxTested = false;
  uint64_t hits = 0;
  double mraysPerSecond() const { return seconds > 0 ? raysTraced / seconds * 1e-6 : 0; }
};

/// Renders one frame into `fb` (its size and AOV set decide what is computed). Threads come
/// from the ambient TBB arena (limit them with tbb::global_control). The result is
/// bit-identical for any thread count, tile size and packet width. FTZ/DAZ are set on every
/// worker. Throws Error for bad settings, a framebuffer that is empty or not the camera's image
/// size, or settings.spp other than the camera's.
RenderStats renderImage(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                        Framebuffer& fb);

/// Renders several frames in one parallel loop over (camera, tile), so small images keep
/// every core busy: frame k of `cameras` into `framebuffers[k]` (sizes as renderImage
/// requires; spp from each camera's description). Each frame is bit-identical to renderImage
/// of it alone; settings.spp is ignored (each camera's own spp is used). `progress`, when set,
/// is called with the number of frames finished so far after each frame completes, from
/// whichever thread finished it, never two calls at once. Returns each frame's stats
/// (seconds: from the call's start to that frame's completion).
std::vector<RenderStats> renderImages(const Scene& scene, const std::vector<const Camera*>& cameras,
                                      const RenderSettings& settings,
                                      std::vector<Framebuffer>& framebuffers,
                                      const std::function<void(size_t)>& progress = {});
/// renderImages into storage held elsewhere (core/aov/frame_pixels.h): frame k into
/// `frames[k]`. Storage whose misses are not written (FramePixels::missesWritten false) gets
/// every value written by the render threads, each tile's misses before its hits, so it may
/// start unwritten; the pixels equal those of a Framebuffer bit for bit.
std::vector<RenderStats> renderImages(const Scene& scene, const std::vector<const Camera*>& cameras,
                                      const RenderSettings& settings,
                                      const std::vector<FramePixels>& frames,
                                      const std::function<void(size_t)>& progress = {});

/// renderImages for cameras of one size W x H into ONE framebuffer of W x (N·H): frame k fills
/// rows [k·H, (k+1)·H), so each AOV is a single (N, H, W[, C]) block (layered hits: (K, N, H,
/// W), layer-major over the stacked image) that a caller can hand out without copying. Each
/// frame's pixels are bit-identical to renderImage of it alone. Throws Error when the cameras'
/// sizes differ or the framebuffer is not W x (N·H).
std::vector<RenderStats> renderImagesStacked(const Scene& scene,
                                             const std::vector<const Camera*>& cameras,
                                             const RenderSettings& settings, Framebuffer& stacked,
                                             const std::function<void(size_t)>& progress = {});
/// renderImagesStacked into storage held elsewhere (renderImages over FramePixels says how
/// its misses are written): the zero-copy arrays of the Python module, fresh or the caller's.
std::vector<RenderStats> renderImagesStacked(const Scene& scene,
                                             const std::vector<const Camera*>& cameras,
                                             const RenderSettings& settings,
                                             const FramePixels& stacked,
                                             const std::function<void(size_t)>& progress = {});

/// Checks settings (packet width in {1,4,8,16}, tile size a positive multiple of 4 up to
/// 4096); throws Error naming the bad value. spp is the camera's, checked by the camera
/// schema; renderImage requires settings.spp to equal it.
void validateRenderSettings(const RenderSettings& settings);

}  // namespace aperture
