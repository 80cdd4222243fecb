#pragma once
// Output paths checked before any work (extensions per role, directories, write permission,
// previewable AOVs, preview depth ranges), and the one depth range every preview of a batch
// shares.
#include <deque>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cameras/schema/params.h"
#include "core/aov/framebuffer.h"
#include "core/io/image.h"
#include "core/mesh/mesh.h"

namespace aperture::app {

/// What an output path is written as.
enum class OutputKind {
  Exr,         ///< the multi-channel EXR (`--out`, the job's "output")
  Preview,     ///< the 8-bit preview (`--preview`, the job's "preview")
  Dataset,     ///< one AOV in a dataset format (`--out x.png` with one AOV, the job's "outputs")
  Visibility,  ///< `aperture visibility --out`: the arrays (.npz) or the mesh with them (.ply)
  Query,       ///< `aperture query --out`: the arrays (.npz)
};

/// The extensions (lower case, with the dot) a kind of output may end in; checks ignore case.
/// Exr: .exr. Preview: previewExtensions() of core/io/image.h (8-bit RGB). Dataset:
/// datasetExtensions() of core/io/dataset_image.h (.png is a 16-bit depth file there, an 8-bit
/// picture as a preview). Visibility: .npz .ply. Query: .npz.
const std::vector<std::string>& supportedExtensions(OutputKind kind);

/// Checks the name of the output file `path`, given as `name` (a flag such as "--out" or a job
/// key such as "output"): it is not an existing directory and does not end in '/' ("is a
/// directory"), and it ends in one of supportedExtensions(kind) (else the message lists them).
/// Throws Error("NAME: 'PATH': reason").
void checkOutputName(const std::string& name, const std::string& path, OutputKind kind);

/// Checks that the directory `dir` that output `path` goes into exists or can be created and
/// that files can be created in it: its nearest existing ancestor must be a directory that is
/// writable and searchable (access(W_OK | X_OK)). Nothing is created. Throws
/// Error("NAME: 'PATH': reason") naming the directory and the reason.
void checkOutputDirectory(const std::string& name, const std::string& path, const std::string& dir);

/// Everything that can be known about writing `path` without writing it: checkOutputName,
/// then checkOutputDirectory of its parent directory ("." for a bare file name).
void checkOutputPath(const std::string& name, const std::string& path, OutputKind kind);

/// The directory of an output pattern up to its first placeholder, as written: "out/" for
/// "out/{camera}/{frame}.exr", "." when the pattern starts with a placeholder or names no
/// directory.
std::string patternDirectory(const std::string& pattern);

/// Refuses a dataset file `path` (given as `name`) that cannot hold `aov` (checkDatasetAov).
/// Throws Error("NAME: 'PATH': AOV ... cannot be written as ...").
void checkDatasetOutput(const std::string& name, const std::string& path, const std::string& aov);

/// Whether a view's files go through the image codec (core/io/image_codec.h), which must then be
/// loaded: any preview, or a dataset file (path or pattern) in a format the codec encodes.
bool writesThroughImageCodec(bool preview, const std::vector<std::string>& datasetPaths);

/// Checks a 16-bit PNG depth scale (`name` is the flag or key): positive and finite.
void checkDepthScale(const std::string& name, double scale);

/// Refuses a preview (`path`, given as `name`) of a framebuffer of `aovs` when none of them can
/// be previewed (previewableAovs of core/io/image.h); the message lists the ones that can.
void checkPreviewable(const std::string& name, const std::string& path, AovMask aovs);

/// Checks a preview depth range [NEAR, FAR]: both finite, 0 <= NEAR < FAR. Throws Error with
/// the reason only; callers prefix the flag or key and the value.
void checkPreviewRange(const glm::dvec2& range);

/// Parses and checks `flag` NEAR,FAR (e.g. "--preview-range 2,10"); throws Error naming the
/// flag and the text.
glm::dvec2 parsePreviewRange(const std::string& flag, const std::string& text);

/// The planar depths Z = dot(P − eye, −W) that the cameras `cameras` can see of points in the
/// world box [lo, hi] lie within the returned [NEAR, FAR]: the minimum (clamped at 0) and the
/// maximum of Z over the box's eight corners and all the cameras (Z is linear in P, so its
/// extremes over a box are at corners). Nothing when FAR <= NEAR (the box is behind every
/// camera) or when there is no camera.
std::optional<glm::dvec2> depthRangeOfBox(const glm::dvec3& lo, const glm::dvec3& hi,
                                          const std::vector<CameraParams>& cameras);

}  // namespace aperture::app
