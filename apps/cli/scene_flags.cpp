#include "apps/cli/scene_flags.h"

namespace aperture::app {

void addSceneOptions(CLI::App& app, SceneOptions& o) {
  app.add_option(
      "--mesh", o.meshes,
      "Mesh or scene file (.ply, .obj with its objects and materials, .gltf or .glb with its "
      "nodes, meshes and materials) or procedural:NAME?k=v (e.g. "
      "procedural:spheres?tris=2000000); repeatable. Default: the procedural default scene");
  app.add_option("--gltf-scene", o.gltfScene,
                 "The scene (index into the file's \"scenes\") of every .gltf/.glb --mesh to "
                 "load. Default: the file's \"scene\", else scene 0")
      ->type_name("N");
  app.add_option("--bvh-quality", o.quality,
                 "Embree BVH build quality: low, medium, high (high lets Embree use spatial "
                 "splits: a slower build for tracing as fast or faster; what Embree builds "
                 "depends on its release and the CPU: Embree 3.13 on a Xeon built robust high, "
                 "the default, as medium, bench/RESULTS.md)")
      ->capture_default_str();
  // One option under two names, so an explicit --no-robust counts as given (--robust) and
  // wins over a preset.
  app.add_flag("--robust,!--no-robust", o.robust,
               "Embree robust (watertight) traversal: on by default; --no-robust trades it for "
               "0-8 % of trace time and lets a few rays in ten million slip through shared edges");
  app.add_flag("--compact", o.compact, "Embree compact BVH (less memory, slower)");
  app.add_option("--bvh-chunk", o.bvhChunk,
                 "Build a mesh of more triangles than this as several BVHs of at most this many, "
                 "one after the other, so Embree's build holds 32 bytes per triangle of one chunk "
                 "rather than of the mesh; a mesh whose triangle order is scattered in space is "
                 "first put in spatial order (primIDs keep the file's order) (0: one BVH per "
                 "mesh; not with --compact)")
      ->capture_default_str();
  app.add_flag("--cull", o.cull,
               "Build the BVH over only the triangles the camera's view volume may reach "
               "(conservative: the image is bit-identical; panoramas keep all)");
  app.add_option("--max-memory", o.maxMemory,
                 "Refuse the job before loading when its estimated memory (mesh buffers from "
                 "the file headers, ~80 bytes/triangle of BVH, framebuffers) exceeds BYTES "
                 "(suffix K, M, G, T) or, with 'auto', MemAvailable");
  app.add_flag("--world-space", o.worldSpace,
               "Store vertices as float32 world coordinates instead of relative to the mesh's "
               "bounding-box centre (camera-relative, the default); for measuring the difference");
}

}  // namespace aperture::app
