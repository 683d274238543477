# run_consumer.cmake: prove that RayCache works as a package. Run with cmake -P; any failure is
# a FATAL_ERROR that names the step and shows its output.
#
#   -DMODE=find_package         install RAYCACHE_BINARY_DIR into a prefix, move the prefix, then
#                               build and run consumers/find_package against the moved prefix
#   -DMODE=add_subdirectory     build and run consumers/add_subdirectory on RAYCACHE_SOURCE_DIR
#   -DMODE=missing_component    find_package(RayCache REQUIRED COMPONENTS NoSuchThing) must fail
#                               at configure; as OPTIONAL_COMPONENTS it must succeed
#   -DMODE=embree_component     find_package(RayCache REQUIRED COMPONENTS Embree) and use Embree
#   -DMODE=old_standard         every public header, compiled as C++11 and C++14, stops at one #error
#                               naming C++17 (old_standard.cmake)
#   -DMODE=vulkan_user          install and move as find_package, then build and run consumers/vulkan_user
#                               (a Vulkan compute program written from the README; its output is shown, so
#                               a skip, no device or no validation layer, reads as one)
# Also: RAYCACHE_SOURCE_DIR, RAYCACHE_BINARY_DIR, CONSUMERS_DIR, WORK_DIR (wiped first), CONFIG,
#       GENERATOR, MAKE_PROGRAM, CXX_COMPILER, PREFIX_PATH ('|'-separated).
cmake_minimum_required(VERSION 3.20)

foreach(_v MODE RAYCACHE_SOURCE_DIR RAYCACHE_BINARY_DIR CONSUMERS_DIR WORK_DIR GENERATOR CXX_COMPILER)
  if(NOT DEFINED ${_v} OR "${${_v}}" STREQUAL "")
    message(FATAL_ERROR "run_consumer.cmake: -D${_v}=... is required")
  endif()
endforeach()
string(REPLACE "|" ";" PREFIX_PATH "${PREFIX_PATH}")
# Search paths go through the environment: a ';' list cannot survive being passed as one argument.
set(_env_prefix_path "$ENV{CMAKE_PREFIX_PATH}")
function(search_prefixes)
  set(_all ${ARGN} ${PREFIX_PATH})
  if(CMAKE_HOST_WIN32)
    set(_sep ";")
  else()
    set(_sep ":")
  endif()
  list(JOIN _all "${_sep}" _joined)
  if(_env_prefix_path)
    string(APPEND _joined "${_sep}${_env_prefix_path}")
  endif()
  set(ENV{CMAKE_PREFIX_PATH} "${_joined}")
endfunction()
search_prefixes()

file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

# step(<description> <expect: OK|FAIL> <output var> COMMAND...): run, show output on surprise.
function(step what expect out_var)
  string(REPLACE ";" " " _pretty "${ARGN}")
  message(STATUS "[${MODE}] ${what}: ${_pretty}")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
  set(${out_var} "${_out}" PARENT_SCOPE)
  if(expect STREQUAL "OK" AND NOT _rc EQUAL 0)
    message(FATAL_ERROR "[${MODE}] FAILED: ${what} (exit ${_rc})\n--- command:\n${_pretty}\n--- output:\n${_out}")
  elseif(expect STREQUAL "FAIL" AND _rc EQUAL 0)
    message(FATAL_ERROR "[${MODE}] FAILED: ${what} was expected to fail but succeeded\n--- command:\n${_pretty}\n--- output:\n${_out}")
  endif()
endfunction()

# Common configure arguments: same compiler and generator as the RayCache build, nothing else
# from it (in particular no sanitizer flags: those are per-target in RayCache's own tests).
set(_configure_args -G "${GENERATOR}" "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}")
if(MAKE_PROGRAM)
  list(APPEND _configure_args "-DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM}")
endif()
if(CONFIG)
  list(APPEND _configure_args "-DCMAKE_BUILD_TYPE=${CONFIG}")
  set(_config_args --config "${CONFIG}")
  set(_ctest_config_args -C "${CONFIG}")
endif()

# install_relocated(<out var>): install the RayCache build into WORK_DIR/staging, then move it to
# WORK_DIR/relocated, so that any absolute path left in the package points nowhere.
function(install_relocated out_var)
  set(_staging "${WORK_DIR}/staging")
  set(_moved "${WORK_DIR}/relocated")
  step("install RayCache" OK _o "${CMAKE_COMMAND}" --install "${RAYCACHE_BINARY_DIR}" --prefix "${_staging}" ${_config_args})
  file(GLOB_RECURSE _cfg "${_staging}/*.cmake")
  if(NOT _cfg)
    message(FATAL_ERROR "[${MODE}] FAILED: the install put no *.cmake files under ${_staging}")
  endif()
  foreach(_f IN LISTS _cfg)
    file(READ "${_f}" _text)
    string(FIND "${_text}" "${_staging}" _at)
    if(NOT _at EQUAL -1)
      message(FATAL_ERROR "[${MODE}] FAILED: ${_f} contains the absolute install prefix ${_staging}; the package is not relocatable")
    endif()
  endforeach()
  file(RENAME "${_staging}" "${_moved}")
  set(${out_var} "${_moved}" PARENT_SCOPE)
endfunction()

# build_and_run(<source dir> <binary dir> <extra configure args>...): configure, build, ctest.
function(build_and_run src bin)
  step("configure consumer" OK _o "${CMAKE_COMMAND}" -S "${src}" -B "${bin}" ${_configure_args} ${ARGN})
  step("build consumer" OK _o "${CMAKE_COMMAND}" --build "${bin}" ${_config_args})
  step("run consumer" OK _o "${CMAKE_CTEST_COMMAND}" --test-dir "${bin}" ${_ctest_config_args} --output-on-failure -V)
  set(_run_output "${_o}" PARENT_SCOPE)
endfunction()

# write_project(<dir> <body>): a throwaway consumer project for the component checks.
function(write_project dir body)
  file(WRITE "${dir}/CMakeLists.txt"
    "cmake_minimum_required(VERSION 3.20)\nproject(raycache_component_check LANGUAGES CXX)\n${body}\n")
endfunction()

if(NOT CMAKE_CTEST_COMMAND)
  get_filename_component(_bin "${CMAKE_COMMAND}" DIRECTORY)
  set(CMAKE_CTEST_COMMAND "${_bin}/ctest")
endif()

if(MODE STREQUAL "find_package")
  install_relocated(_prefix)
  search_prefixes("${_prefix}")
  build_and_run("${CONSUMERS_DIR}/find_package" "${WORK_DIR}/build")

elseif(MODE STREQUAL "add_subdirectory")
  build_and_run("${CONSUMERS_DIR}/add_subdirectory" "${WORK_DIR}/build"
    "-DRAYCACHE_SOURCE_DIR=${RAYCACHE_SOURCE_DIR}")

elseif(MODE STREQUAL "missing_component")
  install_relocated(_prefix)
  search_prefixes("${_prefix}")
  write_project("${WORK_DIR}/required" "find_package(RayCache 0.1 REQUIRED COMPONENTS GLSL NoSuchThing)")
  step("configure with REQUIRED COMPONENTS NoSuchThing" FAIL _o
    "${CMAKE_COMMAND}" -S "${WORK_DIR}/required" -B "${WORK_DIR}/required/build" ${_configure_args})
  if(NOT _o MATCHES "NoSuchThing")
    message(FATAL_ERROR "[${MODE}] FAILED: configure failed but its message does not name the unknown component:\n${_o}")
  endif()
  write_project("${WORK_DIR}/optional" [[
find_package(RayCache 0.1 REQUIRED COMPONENTS GLSL OPTIONAL_COMPONENTS NoSuchThing)
if(RayCache_NoSuchThing_FOUND OR NOT RayCache_GLSL_FOUND OR NOT TARGET RayCache::RayCache)
  message(FATAL_ERROR "optional unknown component handled wrongly")
endif()]])
  step("configure with OPTIONAL_COMPONENTS NoSuchThing" OK _o
    "${CMAKE_COMMAND}" -S "${WORK_DIR}/optional" -B "${WORK_DIR}/optional/build" ${_configure_args})

elseif(MODE STREQUAL "embree_component")
  install_relocated(_prefix)
  search_prefixes("${_prefix}")
  write_project("${WORK_DIR}/embree" [[
find_package(RayCache 0.1 REQUIRED COMPONENTS Embree GLSL)
if(NOT TARGET RayCache::Embree)
  message(FATAL_ERROR "RayCache::Embree missing after find_package(RayCache COMPONENTS Embree)")
endif()
file(WRITE "${CMAKE_BINARY_DIR}/main.cpp" [=[
#include <embree3/rtcore.h>
#include <raycache/raycache.hpp>
int main() {
  RTCDevice device = rtcNewDevice(nullptr);
  if (!device) return 1;
  rtcReleaseDevice(device);
  return 0;
}
]=])
add_executable(embree_consumer "${CMAKE_BINARY_DIR}/main.cpp")
target_link_libraries(embree_consumer PRIVATE RayCache::Embree)
enable_testing()
add_test(NAME embree_consumer COMMAND embree_consumer)]])
  build_and_run("${WORK_DIR}/embree" "${WORK_DIR}/embree/build")

elseif(MODE STREQUAL "vulkan_user")
  install_relocated(_prefix)
  search_prefixes("${_prefix}")
  build_and_run("${CONSUMERS_DIR}/vulkan_user" "${WORK_DIR}/build")
  message(STATUS "[${MODE}] the program's run:\n${_run_output}")

elseif(MODE STREQUAL "old_standard")
  include("${CONSUMERS_DIR}/old_standard.cmake")

else()
  message(FATAL_ERROR "run_consumer.cmake: unknown MODE '${MODE}'")
endif()

message(STATUS "[${MODE}] passed")
