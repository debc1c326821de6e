# Install rules: the runtime and platform libraries, their public headers, the generated version
# header, a CMake package (find_package(lightpatch) gives lightpatch::runtime,
# lightpatch::runtime_core, lightpatch::platform, lightpatch::platform_core, lightpatch::gles)
# with a version file, and pkg-config files (lightpatch.pc: the runtime; lightpatch-platform.pc:
# EGL contexts, file mapping, clocks). The cooker, the tools and the samples are not installed.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(LIGHTPATCH_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/lightpatch)
install(TARGETS ${LIGHTPATCH_EXPORTED_TARGETS} EXPORT lightpatchTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/runtime/include/lightpatch
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.h")
install(FILES ${LIGHTPATCH_GENERATED_INCLUDE}/lightpatch/version.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/lightpatch)
set(platform_headers clock.h file_mapping.h)
if(NOT LIGHTPATCH_RUNTIME_ONLY)
  list(APPEND platform_headers egl_context.h gl.h)
endif()
list(TRANSFORM platform_headers PREPEND ${PROJECT_SOURCE_DIR}/platform/include/lightpatch/platform/)
install(FILES ${platform_headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/lightpatch/platform)

install(EXPORT lightpatchTargets NAMESPACE lightpatch:: DESTINATION ${LIGHTPATCH_CMAKE_DIR})
set(LIGHTPATCH_CONFIG_GLES OFF)
if(NOT LIGHTPATCH_RUNTIME_ONLY AND NOT ANDROID)
  set(LIGHTPATCH_CONFIG_GLES ON)
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/lightpatchConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/lightpatchConfig.cmake
                              INSTALL_DESTINATION ${LIGHTPATCH_CMAKE_DIR})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/lightpatchConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/lightpatchConfig.cmake ${CMAKE_BINARY_DIR}/lightpatchConfigVersion.cmake
        DESTINATION ${LIGHTPATCH_CMAKE_DIR})

# pkg-config. The libraries are static: their system libraries are in Requires.
if(NOT LIGHTPATCH_RUNTIME_ONLY)
  file(RELATIVE_PATH LIGHTPATCH_PC_TO_PREFIX /${CMAKE_INSTALL_LIBDIR}/pkgconfig /)
  string(REGEX REPLACE "/$" "" LIGHTPATCH_PC_TO_PREFIX "${LIGHTPATCH_PC_TO_PREFIX}")
  set(LIGHTPATCH_PC_RUNTIME_REQUIRES "glesv2")
  set(LIGHTPATCH_PC_PLATFORM_REQUIRES "egl glesv2")
  if(LIGHTPATCH_X11_FOUND)
    string(APPEND LIGHTPATCH_PC_PLATFORM_REQUIRES " x11")
  endif()
  foreach(pc lightpatch lightpatch-platform)
    configure_file(${PROJECT_SOURCE_DIR}/cmake/${pc}.pc.in ${CMAKE_BINARY_DIR}/${pc}.pc @ONLY)
    install(FILES ${CMAKE_BINARY_DIR}/${pc}.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
  endforeach()
endif()
