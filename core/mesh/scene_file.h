#pragma once
// Files that hold a scene rather than one mesh: glTF 2.0 (nodes placing meshes, materials,
// textures, cameras) and OBJ (objects and materials). A PLY file or a procedural spec is a
// scene file of one mesh placed once. The loaders fill a SceneFile; the scene set-up
// (apps/services/scene_setup) finishes its meshes and places them.
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"

namespace aperture {

/// How texture coordinates outside [0, 1] wrap (glTF sampler wrapS / wrapT).
enum class TextureWrap { Repeat, ClampToEdge, MirroredRepeat };

/// An image a material samples. Texture coordinate (0, 0) is the top-left corner of the image
/// (glTF; an OBJ's vt, whose origin is the bottom-left, is stored as (u, 1 - v) by its loader).
struct SurfaceTexture {
  std::string where;                 ///< names it in messages: "scene.glb: /images/2", "room.mtl:7"
  std::string path;                  ///< an external image file (resolved); empty when embedded
  std::vector<unsigned char> bytes;  ///< the embedded image (GLB buffer view, data URI)
  std::string mimeType;              ///< "image/png", "image/jpeg" (embedded images)
  TextureWrap wrapS = TextureWrap::Repeat, wrapT = TextureWrap::Repeat;
  bool nearest = false;  ///< magnification filter NEAREST (glTF 9728); else bilinear
  bool srgb = true;      ///< sRGB-encoded (base colour textures are, in glTF and OBJ)
};

/// A material, as far as the albedo AOV reads it.
struct Material {
  std::string name;
  glm::vec4 baseColor{1.0f};  ///< linear RGBA: glTF baseColorFactor, OBJ (Kd, 1)
  int baseColorTexture = -1;  ///< into SceneFile::textures; -1: none
  /// A required extension aperture does not support that makes the base colour unknown
  /// ("KHR_texture_basisu"); empty when supported. The albedo AOV is refused for a scene that
  /// holds such a material, naming the extension.
  std::string unsupported;
};

/// One placement of one of the file's meshes.
struct MeshInstance {
  size_t mesh = 0;                ///< into SceneFile::meshes
  glm::dmat4 worldFromMesh{1.0};  ///< composed in double along the node path (glTF)
  /// The `instance` id of its triangles: glTF the index of the node in the file's `nodes`;
  /// OBJ and PLY 0 (an OBJ adds each triangle's Mesh::faceGroups).
  uint32_t id = 0;
};

/// A glTF camera, placed by its node: it looks down its −Z with +Y up (glTF 2.0, 3.10).
struct SceneCamera {
  std::string name;  ///< the node's name, else "camera_<node index>"
  uint32_t node = 0;
  enum class Projection { Perspective, Orthographic } projection = Projection::Perspective;
  double yfov = 0;                    ///< radians (perspective)
  std::optional<double> aspectRatio;  ///< width / height (perspective; optional in glTF)
  double xmag = 0, ymag = 0;          ///< half-extents (orthographic)
  double znear = 0;
  std::optional<double> zfar;       ///< absent: infinite (perspective)
  glm::dmat4 worldFromCamera{1.0};  ///< the node's world transform, composed in double
};

/// What a scene file holds. Its meshes are as their loader leaves them (world coordinates of
/// the mesh's own space, not finished: finishMesh has not run).
struct SceneFile {
  std::string path;
  std::vector<Mesh> meshes;             ///< glTF: one per `meshes` entry, its primitives in order
  std::vector<MeshInstance> instances;  ///< the placements, in node order (depth first)
  /// The names behind the ids, each indexed by its id: instance (glTF: every node, "node_<k>"
  /// when unnamed; OBJ: the objects in order of first appearance; PLY: the file's stem),
  /// mesh and material.
  std::vector<std::string> instanceNames, meshNames, materialNames;
  std::vector<Material> materials;  ///< indexed by Mesh::faceMaterials
  std::vector<SurfaceTexture> textures;
  std::vector<SceneCamera> cameras;  ///< glTF camera nodes of the loaded scene, in node order
  size_t fileBytes = 0;
  size_t skippedPrimitives = 0;  ///< points and lines (glTF modes 0-3), skipped with a warning
};

/// Loads a glTF 2.0 file (.gltf with its buffers, or .glb). Throws Error naming the file and a
/// JSON pointer to the offending element ("scene.glb: /accessors/3/count: ...").
SceneFile loadGltf(const std::string& path, const LoadOptions& options = {});
/// The same on a file in memory (`name` stands for it; external URIs resolve beside `name`).
SceneFile loadGltfFromMemory(const char* data, size_t size, const std::string& name,
                             const LoadOptions& options = {});
/// An OBJ with its objects (o, g), materials (usemtl) and material libraries (mtllib: Kd,
/// map_Kd relative to the .mtl): one mesh (as loadObj leaves it, and with the per-triangle
/// object and material ids when LoadOptions::groups / materials ask) placed once with id 0.
/// instanceNames: the objects in id order (faces before any o/g: an object named after the
/// file's stem); materialNames and materials: the usemtl names in order of first appearance,
/// then "default" (white) when faces come before any usemtl. Material::baseColor is (Kd, 1),
/// Kd taken as linear RGB as the file writes it; (1, 1, 1, 1) for a name no library defines or
/// an entry without Kd. A map_Kd of a used material is a texture (Repeat unless `-clamp on`,
/// sRGB, bilinear). Errors name the file and line: an mtllib that cannot be read (the .obj's
/// line and the path tried), a map_Kd file that does not exist or an option that changes the
/// mapping (-s, -o, -t; the .mtl's line). The details of both formats: core/mesh/obj.cpp and
/// core/mesh/mtl.cpp.
SceneFile loadObjScene(const std::string& path, const LoadOptions& options = {});
/// The same on a file in memory (`name` stands for it; mtllib paths resolve beside `name`).
/// Used by the fuzz target.
SceneFile loadObjSceneFromMemory(const char* data, size_t size, const std::string& name,
                                 const LoadOptions& options = {});

/// True for the extensions of files that hold scenes of several meshes (.gltf, .glb).
bool isGltfPath(const std::string& path);

/// Any mesh spec as a scene file: glTF, OBJ with its groups and materials, or one mesh (PLY,
/// procedural) placed once. Meshes are not finished.
SceneFile loadSceneFile(const std::string& spec, const LoadOptions& options = {});

/// Linear RGBA of textures at texture coordinates, with their wrap and filter modes. The one
/// implementation samples through OpenImageIO's TextureSystem (core/io/texture_sampler.h).
class TextureSampler {
 public:
  virtual ~TextureSampler() = default;
  /// Texture `texture` (an index into the SceneFile::textures it was made from) at (s, t).
  virtual glm::vec4 sample(int texture, float s, float t) const = 0;
};

/// What the albedo AOV reads, scene-wide: the materials by their scene id and the sampler of
/// their textures (null when no material has one).
struct SurfaceLooks {
  std::vector<Material> materials;
  std::shared_ptr<const TextureSampler> textures;
};

}  // namespace aperture
