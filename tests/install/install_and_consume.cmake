# Script mode (tests/install/CMakeLists.txt): install BUILD_DIR into WORK_DIR/prefix, build the
# consumer with find_package and with pkg-config, run both on PACK.
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "${what}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
run("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(f include/lightpatch/runtime.h include/lightpatch/version.h
          include/lightpatch/platform/egl_context.h lib/cmake/lightpatch/lightpatchConfig.cmake
          lib/cmake/lightpatch/lightpatchConfigVersion.cmake lib/pkgconfig/lightpatch.pc)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
# Nothing of the cooker, the tools or the samples.
file(GLOB_RECURSE installed RELATIVE ${prefix} ${prefix}/*)
foreach(f ${installed})
  if(f MATCHES "cooker|scenegen|inn|bin/")
    message(FATAL_ERROR "installed a file that is not the runtime's: ${f}")
  endif()
endforeach()

# find_package, with the version asked for.
run("configure the consumer" ${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${WORK_DIR}/consumer -G ${GENERATOR}
    -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_PREFIX_PATH=${prefix} -DLIGHTPATCH_WANTED=${VERSION})
run("build the consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/consumer)
run("run the consumer" ${WORK_DIR}/consumer/lightpatch_consumer ${PACK})
message(STATUS "${last_output}")
if(NOT last_output MATCHES "lightpatch ${VERSION}")
  message(FATAL_ERROR "the consumer did not report version ${VERSION}")
endif()

# The runtime's public link interface: GLES and the core, no EGL, no X11.
file(READ ${prefix}/lib/cmake/lightpatch/lightpatchTargets.cmake targets)
string(REGEX MATCH "set_target_properties\\(lightpatch::runtime PROPERTIES[^)]*\\)" runtime_props "${targets}")
if(runtime_props MATCHES "X11|EGL|platform")
  message(FATAL_ERROR "lightpatch::runtime drags more than GLES into its link interface:\n${runtime_props}")
endif()

# pkg-config, relocated prefix included.
set(ENV{PKG_CONFIG_PATH} ${prefix}/lib/pkgconfig)
run("pkg-config" pkg-config --cflags --libs lightpatch lightpatch-platform)
string(STRIP "${last_output}" flags)
separate_arguments(flags UNIX_COMMAND "${flags}")
run("compile with pkg-config" ${CXX} -std=c++20 ${CONSUMER_DIR}/main.cpp ${flags}
    -o ${WORK_DIR}/consumer_pc)
run("run the pkg-config build" ${WORK_DIR}/consumer_pc ${PACK})
