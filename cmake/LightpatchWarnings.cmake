# Warning and sanitizer flags shared by every lightpatch target.
add_library(lightpatch_flags INTERFACE)
if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  target_compile_options(lightpatch_flags INTERFACE -Wall -Wextra -Wnon-virtual-dtor)
  if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    target_compile_options(lightpatch_flags INTERFACE -Wno-shadow-field-in-constructor)
  endif()
  if(LIGHTPATCH_WERROR)
    target_compile_options(lightpatch_flags INTERFACE -Werror)
  endif()
  if(LIGHTPATCH_SANITIZE)
    target_compile_options(lightpatch_flags INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer
                                                      -fno-sanitize-recover=undefined)
    target_link_options(lightpatch_flags INTERFACE -fsanitize=address,undefined)
  endif()
endif()

# Adds a GoogleTest executable for one module and registers its tests with CTest.
# LABELS: "unit" tests also run under ASan+UBSan; "gles" tests need an EGL/GLES driver.
function(lightpatch_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS;LABELS;ENVIRONMENT" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main lightpatch_flags)
  target_compile_definitions(${name} PRIVATE LIGHTPATCH_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data")
  if(ARG_ENVIRONMENT)
    gtest_discover_tests(${name} PROPERTIES LABELS "${ARG_LABELS}" ENVIRONMENT "${ARG_ENVIRONMENT}"
                         DISCOVERY_TIMEOUT 60)
  else()
    gtest_discover_tests(${name} PROPERTIES LABELS "${ARG_LABELS}" DISCOVERY_TIMEOUT 60)
  endif()
endfunction()
