# 64-bit Arm Linux (a phone's CPU) with Debian's g++-aarch64-linux-gnu. With
# -DLIGHTPATCH_RUNTIME_ONLY=ON it builds the runtime's CPU parts and their tests; with
# -DLIGHTPATCH_DEVICE=ON the runtime with its GLES recomposer against Debian's arm64 EGL/GLES/Mesa
# packages (multiarch: libegl-dev:arm64 libgles-dev:arm64 libegl-mesa0:arm64
# libgl1-mesa-dri:arm64, which ./run deps installs) and the GLES tests on synthetic packs. ctest
# runs them under qemu-aarch64 (GLES on Mesa's llvmpipe, JIT-compiling arm64 code).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
# The cross compiler's own root, and / for the multiarch libraries in /usr/lib/aarch64-linux-gnu.
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config reads the arm64 .pc files only (egl, glesv2, x11 of the arm64 packages).
set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig)
set(ENV{PKG_CONFIG_PATH} "")
# qemu with / as the guest root: the arm64 loader and libraries of Debian's libc6:arm64 (a
# dependency of the Mesa packages), which also find /usr/lib/aarch64-linux-gnu.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64;-L;/)
# GoogleTest is compiled from Debian's sources (/usr/src/googletest) for the target.
set(LIGHTPATCH_GTEST_FROM_SOURCE ON CACHE BOOL "")
