# RayCacheSanitize.cmake: sanitizer flags for RayCache's own test and example targets only.
#
# raycache_target_sanitize(<target>)
#   Adds -fsanitize=${RAYCACHE_SANITIZE} -fno-omit-frame-pointer -g to the target's compile and
#   link options (PRIVATE: nothing propagates to consumers). No-op when RAYCACHE_SANITIZE is empty.
# raycache_sanitize_directory(<dir>)
#   Calls raycache_target_sanitize on every compiled target defined in <dir> and below
#   (used for examples, whose CMakeLists need not know about sanitizers).
# RAYCACHE_VULKAN_LSAN_ENVIRONMENT
#   "LSAN_OPTIONS=suppressions=<cmake/lsan_vulkan.supp>": the ENVIRONMENT of every test that loads Vulkan.
#   Leak checking stays on; only blocks allocated inside the Vulkan loader, its drivers (lavapipe, LLVM)
#   and layers are suppressed, by module name (the file says which and why). Quoted for LeakSanitizer's
#   option parser, which splits on spaces, commas and colons.
include_guard(GLOBAL)

set(RAYCACHE_VULKAN_LSAN_ENVIRONMENT "LSAN_OPTIONS=suppressions='${CMAKE_CURRENT_LIST_DIR}/lsan_vulkan.supp'")

set(_RAYCACHE_SANITIZE_ALLOWED "" "address,undefined" "address" "undefined" "thread")
if(DEFINED RAYCACHE_SANITIZE AND NOT RAYCACHE_SANITIZE IN_LIST _RAYCACHE_SANITIZE_ALLOWED)
  message(FATAL_ERROR "RAYCACHE_SANITIZE='${RAYCACHE_SANITIZE}' is not supported; use one of: "
                      "\"\" (off), \"address,undefined\", \"address\", \"undefined\", \"thread\".")
endif()

function(raycache_target_sanitize target)
  if(NOT RAYCACHE_SANITIZE)
    return()
  endif()
  get_target_property(_done ${target} RAYCACHE_SANITIZED)
  if(_done)
    return()
  endif()
  set(_flags "-fsanitize=${RAYCACHE_SANITIZE}" -fno-omit-frame-pointer -g)
  if(RAYCACHE_SANITIZE MATCHES "undefined")
    # Make every UB report fatal even without UBSAN_OPTIONS=halt_on_error=1.
    list(APPEND _flags -fno-sanitize-recover=undefined)
  endif()
  target_compile_options(${target} PRIVATE ${_flags})
  target_link_options(${target} PRIVATE "-fsanitize=${RAYCACHE_SANITIZE}")
  set_target_properties(${target} PROPERTIES RAYCACHE_SANITIZED ON)
endfunction()

function(raycache_sanitize_directory dir)
  get_property(_targets DIRECTORY "${dir}" PROPERTY BUILDSYSTEM_TARGETS)
  foreach(_t IN LISTS _targets)
    get_target_property(_type ${_t} TYPE)
    if(_type MATCHES "^(EXECUTABLE|STATIC_LIBRARY|SHARED_LIBRARY|MODULE_LIBRARY|OBJECT_LIBRARY)$")
      raycache_target_sanitize(${_t})
    endif()
  endforeach()
  get_property(_subdirs DIRECTORY "${dir}" PROPERTY SUBDIRECTORIES)
  foreach(_d IN LISTS _subdirs)
    raycache_sanitize_directory("${_d}")
  endforeach()
endfunction()
