// tinygltf's implementation, compiled here with the settings of gltf.h (no image decoding or
// writing, no reading of external images, its own namespace) rather than linked from Debian's
// libtinygltf.so, whose image loading needs libstb and which cannot be renamed.
#define TINYGLTF_IMPLEMENTATION
#include "core/mesh/gltf.h"
