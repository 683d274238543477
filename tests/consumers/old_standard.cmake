# old_standard.cmake (run_consumer.cmake's MODE=old_standard): a consumer built as C++11 or C++14 must
# stop at RayCache's one #error naming the requirement (raycache/requires_cpp17.hpp), not at a hundred
# errors from inside the headers. For every public header and each of those standards, compiles a
# one-line consumer `#include <that header>` the way a Makefile-built tracer would (no CMake target, so
# nothing raises the standard) and checks the compiler's output: the #error's exact message, once, and no
# other error but the stop that follows it. Needs a GCC- or Clang-like CXX_COMPILER.
set(_standards c++11 c++14)

# The message a user sees; a change to it in requires_cpp17.hpp must be made here too, on purpose.
set(_expected "RayCache needs C++17 or later: compile with -std=c++17 (CMake: link RayCache::RayCache, which asks for cxx_std_17)")

set(_core "${RAYCACHE_SOURCE_DIR}/include")
set(_embree "${RAYCACHE_SOURCE_DIR}/adapters/embree/include")
file(GLOB _headers RELATIVE "${_core}" "${_core}/raycache/*.hpp")
file(GLOB _adapter_headers RELATIVE "${_embree}" "${_embree}/raycache/embree/*.hpp")
list(APPEND _headers ${_adapter_headers})
list(LENGTH _headers _count)
if(_count LESS 10)
  message(FATAL_ERROR "[${MODE}] FAILED: found only ${_count} public headers under ${_core} and ${_embree}")
endif()

set(_failures "")
foreach(_standard IN LISTS _standards)
  foreach(_header IN LISTS _headers)
    string(MAKE_C_IDENTIFIER "${_standard}_${_header}" _name)
    set(_source "${WORK_DIR}/${_name}.cpp")
    file(WRITE "${_source}" "#include <${_header}>\n")
    execute_process(COMMAND "${CXX_COMPILER}" -std=${_standard} -fsyntax-only -I "${_core}" -I "${_embree}" "${_source}"
                    RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
    # Every "file:line:column: error" diagnostic: the #error (GCC: `error: #error "..."`, Clang:
    # `error: "..."`) and the fatal missing include that stops the compiler right after it, nothing else.
    string(REGEX REPLACE "[][;]" "_" _text "${_out}") # one list item a line, brackets and all
    string(REPLACE "\n" ";" _lines "${_text}")
    set(_ours 0)
    set(_stops 0)
    set(_others "")
    foreach(_line IN LISTS _lines)
      if(NOT _line MATCHES ":[0-9]+:[0-9]+: (fatal )?error: ")
        continue()
      endif()
      string(FIND "${_line}" "error: #error \"${_expected}\"" _gcc)
      string(FIND "${_line}" "error: \"${_expected}\"" _clang)
      if(_line MATCHES ": error: " AND (NOT _gcc EQUAL -1 OR NOT _clang EQUAL -1))
        math(EXPR _ours "${_ours} + 1")
      elseif(_line MATCHES ": fatal error: .?RayCache stops here: C\\+\\+17 is required")
        math(EXPR _stops "${_stops} + 1")
      else()
        list(APPEND _others "${_line}")
      endif()
    endforeach()
    if(_rc EQUAL 0 OR NOT _ours EQUAL 1 OR NOT _stops EQUAL 1 OR _others)
      string(APPEND _failures "\n--- -std=${_standard} #include <${_header}>: exit ${_rc}, the #error ${_ours} times, "
                              "the stop ${_stops} times (want 1 and 1, nothing else); output:\n${_out}")
    endif()
  endforeach()
endforeach()

if(_failures)
  message(FATAL_ERROR "[${MODE}] FAILED: a consumer under an old standard did not get exactly RayCache's #error:${_failures}")
endif()
message(STATUS "[${MODE}] ${_count} headers x (${_standards}): each stopped at the one #error \"${_expected}\"")
