#include "apps/cli/render_flags.h"

#include "core/aov/aov_table.h"
#include "core/util/error.h"

namespace aperture::app {

const char* const kLayersHelp =
    "Also record the first K surfaces along each pixel-centre ray, K in [1, 64]: EXR channels "
    "hit<k>.Z hit<k>.T hit<k>.primID hit<k>.geomID for k = 0..K-1, nearest first "
    "(docs/layers.md)";

void addLayersOption(CLI::App& app, std::optional<int>& layers, const std::string& group) {
  CLI::Option* o = app.add_option("--layers", layers, kLayersHelp)->type_name("K");
  if (!group.empty()) o->group(group);
}

void addDeepOption(CLI::App& app, bool& deep, const std::string& group) {
  CLI::Option* o = app.add_flag("--deep", deep,
                                "With --layers K: write the layers as a deep EXR (samples Z, "
                                "ZBack, T, primID, geomID, nearest first) to <out stem>.deep.exr "
                                "instead of hit<k>.* channels (docs/layers.md)");
  if (!group.empty()) o->group(group);
}

void addRenderOptions(CLI::App& app, RenderOptions& o) {
  app.add_option("--aov", o.aovs,
                 cat("AOVs to compute: ", aovNameList(),
                     ", face.NAME, vertex.NAME (integer PLY properties)"))
      ->capture_default_str();
  app.add_option("--normal-frame", o.normalFrame,
                 "Frame of normal and shading-normal: world, opencv (x right, y down, z "
                 "forward) or opengl (x right, y up, z backwards), the camera's axes")
      ->capture_default_str();
  addLayersOption(app, o.layers);
  app.add_option("--packet", o.packet, "Rays per Embree call: 1, 4, 8 or 16")
      ->capture_default_str();
  app.add_option("--tile", o.tile, "Tile size in pixels: a multiple of 4 in [4, 4096]")
      ->capture_default_str();
  app.add_option("--threads", o.threads,
                 "Worker threads in [0, 4096] (0 = all cores): rendering, BVH builds and "
                 "OpenEXR's encoding of the files")
      ->capture_default_str();
}

}  // namespace aperture::app
