# Android, arm64-v8a, GLES 3 + EGL, through the Android NDK's own toolchain file. Builds the
# runtime with its GLES recomposer and the platform's EGL layer (-DLIGHTPATCH_DEVICE=ON is implied:
# the cooker and the samples are host tools), plus the runtime's tests as executables to push to
# a device (adb push; runtime_tests need no GPU, gles_tests need EGL and GLES 3). The NDK is not a
# Debian package and cannot be installed here, so this file has never been built on this machine
# (./run test builds the same LIGHTPATCH_DEVICE configuration for aarch64 Linux with Debian's
# arm64 Mesa and runs it under qemu instead): point it at your NDK with
#   cmake -S . -B build-android -G Ninja -DCMAKE_TOOLCHAIN_FILE=toolchains/android-arm64-v8a.cmake \
#         -DANDROID_NDK=/path/to/android-ndk [-DANDROID_PLATFORM=android-24]
# (or set ANDROID_NDK_HOME / ANDROID_NDK in the environment). GoogleTest is compiled from source
# with -DLIGHTPATCH_GTEST_SOURCE=/path/to/googletest, or leave tests off with
# -DLIGHTPATCH_BUILD_TESTS=OFF.
if(NOT ANDROID_NDK)
  if(DEFINED ENV{ANDROID_NDK_HOME})
    set(ANDROID_NDK $ENV{ANDROID_NDK_HOME})
  elseif(DEFINED ENV{ANDROID_NDK})
    set(ANDROID_NDK $ENV{ANDROID_NDK})
  endif()
endif()
if(NOT ANDROID_NDK OR NOT EXISTS "${ANDROID_NDK}/build/cmake/android.toolchain.cmake")
  message(FATAL_ERROR "android-arm64-v8a.cmake: set -DANDROID_NDK=/path/to/android-ndk (a folder "
                      "holding build/cmake/android.toolchain.cmake); got '${ANDROID_NDK}'")
endif()
set(ANDROID_ABI arm64-v8a CACHE STRING "")
if(NOT ANDROID_PLATFORM)
  set(ANDROID_PLATFORM android-24 CACHE STRING "")  # GLES 3.2 headers, EGL 1.4
endif()
set(ANDROID_STL c++_static CACHE STRING "")
set(LIGHTPATCH_DEVICE ON CACHE BOOL "")
include("${ANDROID_NDK}/build/cmake/android.toolchain.cmake")
