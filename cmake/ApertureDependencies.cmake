# Finds every dependency; a missing one stops configuration with the Debian package to install.
macro(aperture_require pkg debian)
  find_package(${pkg} ${ARGN} QUIET)
  if(NOT ${pkg}_FOUND)
    message(FATAL_ERROR "aperture: dependency '${pkg}' not found. On Debian 12 install it with:\n"
      "  apt-get install ${debian}\n(or run scripts/install-deps.sh, which installs everything)")
  endif()
endmacro()

aperture_require(embree libembree-dev 3.13)
aperture_require(TBB libtbb-dev)
aperture_require(OpenEXR libopenexr-dev)
aperture_require(OpenImageIO libopenimageio-dev)
aperture_require(glm libglm-dev)
aperture_require(nlohmann_json nlohmann-json3-dev)
aperture_require(CLI11 libcli11-dev)
find_package(Threads REQUIRED)
if(APERTURE_BUILD_TESTS)
  aperture_require(GTest "googletest libgtest-dev")
endif()
if(APERTURE_BUILD_BENCH)
  aperture_require(benchmark libbenchmark-dev)
endif()

# Debian 12's OpenImageIO config lists /usr/include/opencv4 (an optional build dependency of
# the package) among its include directories; CMake rejects a missing path, so drop any that
# do not exist instead of installing OpenCV.
foreach(target OpenImageIO::OpenImageIO OpenImageIO::OpenImageIO_Util)
  get_target_property(dirs ${target} INTERFACE_INCLUDE_DIRECTORIES)
  if(dirs)
    set(kept)
    foreach(dir IN LISTS dirs)
      if(EXISTS "${dir}")
        list(APPEND kept "${dir}")
      endif()
    endforeach()
    set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${kept}")
  endif()
endforeach()
