# Fails unless include/raycache/raycache.hpp, "the whole core library", includes every header of
# include/raycache/ (itself and requires_cpp17.hpp, which every header includes, excepted): a header added
# later and left out means a user of the umbrella cannot find its names.
# Usage: cmake -DINCLUDE_DIR=<repo>/include -P umbrella_complete.cmake
file(READ "${INCLUDE_DIR}/raycache/raycache.hpp" umbrella)
file(GLOB headers RELATIVE "${INCLUDE_DIR}" "${INCLUDE_DIR}/raycache/*.hpp")
set(missing "")
foreach(h IN LISTS headers)
  if(h STREQUAL "raycache/raycache.hpp" OR h STREQUAL "raycache/requires_cpp17.hpp")
    continue()
  endif()
  string(FIND "${umbrella}" "#include \"${h}\"" at)
  if(at EQUAL -1)
    list(APPEND missing "${h}")
  endif()
endforeach()
list(LENGTH headers count)
if(missing)
  message(FATAL_ERROR "raycache/raycache.hpp does not include: ${missing}")
endif()
message(STATUS "raycache/raycache.hpp includes all ${count} headers but itself and requires_cpp17.hpp")
