# 64-bit Arm Linux (a phone's CPU) with Debian's g++-aarch64-linux-gnu. Builds the runtime's CPU
# parts and their tests (-DLIGHTPATCH_RUNTIME_ONLY=ON); ctest runs them under qemu-aarch64.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64;-L;/usr/aarch64-linux-gnu)
# GoogleTest is compiled from Debian's sources (/usr/src/googletest) for the target.
set(LIGHTPATCH_GTEST_FROM_SOURCE ON CACHE BOOL "")
