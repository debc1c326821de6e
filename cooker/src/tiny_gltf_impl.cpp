// The one translation unit that compiles tinygltf (and stb_image, which it uses for textures).
//
// Draco: tinygltf's own KHR_draco_mesh_compression path indexes bufferViews without checking the
// index and rewrites the model in place, which a hostile file can turn into a crash. import.cpp
// decodes the extension itself with Draco's API (checking every index), so tinygltf is compiled
// here without it and simply keeps the extension object on the primitive.
#undef TINYGLTF_ENABLE_DRACO

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define STB_IMAGE_IMPLEMENTATION
#define STBI_NO_STDIO_WARNINGS

#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wall"
#pragma clang diagnostic ignored "-Wextra"
#elif defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#endif

#include <tiny_gltf.h>

#if defined(__clang__)
#pragma clang diagnostic pop
#elif defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
