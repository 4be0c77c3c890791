# Helpers shared by every module: one library per libs/<mod>, one gtest binary per test file.

set(IMMSLAM_WARNINGS -Wall -Wextra -Wpedantic -Wnon-virtual-dtor)
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  list(APPEND IMMSLAM_WARNINGS -Wshadow=local)  # gcc only (clang has no =local variant)
endif()

# immslam_add_library(<mod> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates target immslam_<mod> (alias immslam::<mod>) from libs/<mod>/{include,src}.
function(immslam_add_library mod)
  cmake_parse_arguments(A "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(immslam_${mod} ${A_SOURCES})
  add_library(immslam::${mod} ALIAS immslam_${mod})
  target_include_directories(immslam_${mod} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:include>)
  target_link_libraries(immslam_${mod} PUBLIC ${A_PUBLIC_DEPS} PRIVATE ${A_PRIVATE_DEPS})
  target_compile_options(immslam_${mod} PRIVATE ${IMMSLAM_WARNINGS}
    $<$<BOOL:${IMMSLAM_WERROR}>:-Werror>)
  set_target_properties(immslam_${mod} PROPERTIES EXPORT_NAME ${mod} OUTPUT_NAME immslam-${mod})
  install(TARGETS immslam_${mod} EXPORT immslamTargets
    LIBRARY DESTINATION lib ARCHIVE DESTINATION lib RUNTIME DESTINATION bin)
  install(DIRECTORY include/ DESTINATION include)
endfunction()

# immslam_add_app(<name> SOURCES ... DEPS ...)
function(immslam_add_app name)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${A_SOURCES})
  target_link_libraries(${name} PRIVATE ${A_DEPS})
  target_compile_options(${name} PRIVATE ${IMMSLAM_WARNINGS})
  install(TARGETS ${name} RUNTIME DESTINATION bin)
endfunction()

# immslam_add_test(<name> SOURCES ... DEPS ... [LABELS ...] [TIMEOUT s])
# One gtest binary; each TEST becomes one ctest entry. GTEST_SKIP() shows as "skipped".
function(immslam_add_test name)
  cmake_parse_arguments(A "" "TIMEOUT" "SOURCES;DEPS;LABELS" ${ARGN})
  if(NOT A_TIMEOUT)
    set(A_TIMEOUT 600)
  endif()
  add_executable(${name} ${A_SOURCES})
  target_link_libraries(${name} PRIVATE ${A_DEPS} GTest::gtest GTest::gtest_main)
  target_compile_options(${name} PRIVATE ${IMMSLAM_WARNINGS})
  target_compile_definitions(${name} PRIVATE
    IMMSLAM_SHARED_DATA_DIR="${IMMSLAM_SHARED_DATA_DIR}"
    IMMSLAM_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    IMMSLAM_BINARY_DIR="${PROJECT_BINARY_DIR}")
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  gtest_discover_tests(${name}
    WORKING_DIRECTORY ${CMAKE_BINARY_DIR}
    DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS "${A_LABELS}" TIMEOUT ${A_TIMEOUT} SKIP_REGULAR_EXPRESSION "\\[  SKIPPED \\]")
endfunction()
