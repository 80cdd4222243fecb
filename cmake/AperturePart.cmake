# The parts of aperture and the arrows between them, written once. A part is a folder with one
# static library, aperture::<folder with _ for />, built from the folder's .cpp files. The
# parts a part lists are the ones its files may include and its library links; what those
# parts may include, it may include too. Nothing else: tests/check_parts.py reads this table
# and fails the suite on an include it does not allow, on a source file outside every part
# and on a part folder of more than 20 source files.
set(APERTURE_PARTS
  "core/util:"                                       # errors, numbers, parallel loops, kernels, files
  "core/aov: core/util"                              # AOVs: names, channels, framebuffers
  "core/mesh: core/aov"                              # meshes: PLY, OBJ, procedural
  "core/engine: core/mesh"                           # Embree scene, packets, the frame loop, culling
  "core/queries: core/engine"                        # rays and face visibility beside the frame loop
  "core/io: core/engine"                             # image, NumPy and PLY files, atomic writes
  "core/exr: core/io"                                # EXR files and their headers
  "core/points: core/exr"                            # point clouds, range images, their writers
  "cameras/schema: core/util"                        # camera parameters, their specs, conventions
  "cameras/lenses: core/util"                        # calibrated lens models and their inverse
  "cameras/files: cameras/lenses core/io"            # COLMAP, NeRF, OpenCV camera files; points
  "cameras/geometry: core/engine"                    # the camera frame, view volumes
  "cameras/models: cameras/schema cameras/lenses cameras/geometry"  # the camera models
  "cameras/registry: cameras/models"                 # the list of models; describe, culling
  "cameras/lidar: cameras/geometry core/queries"     # LiDAR sensors, trajectories, rolling shutter
  "apps/services: cameras/registry cameras/files cameras/lidar core/points core/queries"  # scene set-up, one view, outputs, scans
  "apps/queries: core/queries core/io"               # point queries: what --what asks, their arrays
  "apps/jobs: apps/services"                         # job files
  "apps/batch: apps/jobs"                            # batches: writers, resume, shards, summaries
  "bench/measure: apps/services"                     # scaling, trade-off study, the bare-Embree baseline
  "apps/cli: apps/batch bench/measure apps/queries"  # the aperture command line
  "python/src: apps/jobs apps/queries"               # the Python module (links no CLI part)
)

# Library headers and the part that owns each: only that part, and the parts that may include
# it, may include them (so the Python module, which links no CLI part, has no CLI11 in it).
set(APERTURE_PART_LIBRARIES
  "CLI/: apps/cli"
  "embree3/: core/engine"
  "OpenEXR/: core/exr"
  "Imath/: core/exr"
  "OpenImageIO/: core/io"
  "yaml-cpp/: cameras/files cameras/lidar"
  "tiny_gltf.h: core/mesh"
  "draco/: core/mesh"
  "meshoptimizer.h: core/mesh"
)

# The parts `part` lists.
function(aperture_part_deps part out)
  set(deps)
  foreach(row IN LISTS APERTURE_PARTS)
    string(REGEX MATCH "^([^:]+):(.*)$" _ "${row}")
    if(CMAKE_MATCH_1 STREQUAL part)
      separate_arguments(deps UNIX_COMMAND "${CMAKE_MATCH_2}")
      set(${out} ${deps} PARENT_SCOPE)
      return()
    endif()
  endforeach()
  message(FATAL_ERROR "aperture: ${part} is not in APERTURE_PARTS (cmake/AperturePart.cmake)")
endfunction()

# aperture_target_of(core/engine out): aperture_core_engine.
function(aperture_target_of part out)
  string(REPLACE "/" "_" name "${part}")
  set(${out} aperture_${name} PARENT_SCOPE)
endfunction()

# In a part's folder: aperture_part([UNITY] [EXCLUDE file.cpp...] [PUBLIC libs...]
# [PRIVATE libs...]) makes its library from the folder's .cpp files, linked to the parts the
# table lists and to the given libraries. UNITY compiles it in unity batches when
# APERTURE_UNITY_BUILD is on (not for parts with hot loops).
function(aperture_part)
  cmake_parse_arguments(P "UNITY" "" "EXCLUDE;PUBLIC;PRIVATE" ${ARGN})
  file(RELATIVE_PATH part ${PROJECT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR})
  aperture_target_of(${part} target)
  aperture_part_deps(${part} deps)
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  foreach(excluded IN LISTS P_EXCLUDE)
    list(REMOVE_ITEM sources ${CMAKE_CURRENT_SOURCE_DIR}/${excluded})
  endforeach()
  add_library(${target} STATIC ${sources})
  string(REPLACE "aperture_" "aperture::" alias ${target})
  add_library(${alias} ALIAS ${target})
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
  set(dep_targets)
  foreach(dep IN LISTS deps)
    aperture_target_of(${dep} dep_target)
    list(APPEND dep_targets ${dep_target})
  endforeach()
  target_link_libraries(${target} PUBLIC ${dep_targets} ${P_PUBLIC}
    PRIVATE ${P_PRIVATE} aperture_warnings)
  if(P_UNITY)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ${APERTURE_UNITY_BUILD})
  endif()
endfunction()
