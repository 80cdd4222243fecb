#pragma once
// Wavefront material libraries (.mtl), as far as the OBJ scene loader reads them: `newmtl`,
// `Kd` and `map_Kd`. Every other statement is ignored.
#include <cstddef>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "core/mesh/scene_file.h"

namespace aperture {

/// One `newmtl` entry.
struct MtlMaterial {
  std::string name;
  /// `Kd r g b` (or `Kd r`: g = b = r) as the file says, taken as linear RGB; (1, 1, 1) when
  /// the entry has no Kd.
  glm::vec3 kd{1.0f};
  /// `map_Kd [options] file`: the file resolved beside the .mtl, empty when the entry has none.
  std::string mapKd;
  size_t mapKdLine = 0;                    ///< the line of the map_Kd statement
  TextureWrap wrap = TextureWrap::Repeat;  ///< Repeat (OBJ's default); `-clamp on`: ClampToEdge
  /// Why the map_Kd cannot be honoured (an option that changes the mapping, such as -s, -o or
  /// -t); empty when it can. Thrown only when a face uses the material (see loadObjScene).
  std::string mapKdProblem;
};

/// The entries of one .mtl file, in file order.
struct MtlLibrary {
  std::string path;
  std::vector<MtlMaterial> materials;
};

/// Parses the .mtl text `size` bytes at `data`; `path` names it in messages and is the
/// directory map_Kd paths are relative to. Throws Error naming path:line for a statement it
/// reads that is malformed (Kd that is not 1 or 3 finite numbers, Kd before any newmtl, a
/// newmtl without a name).
MtlLibrary parseMtl(const char* data, size_t size, const std::string& path);

/// `relative` resolved against the directory of `file` ("dir/room.obj", "a.mtl" ->
/// "dir/a.mtl"); an absolute `relative` is returned as is.
std::string pathBeside(const std::string& file, const std::string& relative);

}  // namespace aperture
