# RayCacheGLSL.cmake: compile GLSL that includes RayCache's shader headers to SPIR-V.
#
# raycache_add_glsl_shader(TARGET <target> SOURCE <file> OUTPUT <file.spv>
#                          [STAGE <comp|frag|vert|rgen|...>] [DEFINES <NAME[=VALUE]>...]
#                          [INCLUDE_DIRS <dir>...])
#   Runs glslangValidator --target-env vulkan1.1 -I<RayCache GLSL include dir> at build time and
#   makes <target> depend on the .spv. Relative SOURCE is from the current source dir, relative
#   OUTPUT from the current binary dir. STAGE defaults to what glslang infers from the extension;
#   ray tracing stages (rgen, rint, rahit, rchit, rmiss, rcall) also get --target-env spirv1.4,
#   which GL_EXT_ray_tracing requires under Vulkan 1.1.
#   The include dir comes from the RayCache::GLSL target (property INTERFACE_RAYCACHE_GLSL_INCLUDE_DIR)
#   or else the RayCache_GLSL_INCLUDE_DIR variable; it works after find_package(RayCache) and after
#   add_subdirectory(RayCache) alike.
include_guard(GLOBAL)

function(raycache_add_glsl_shader)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "TARGET;SOURCE;OUTPUT;STAGE" "DEFINES;INCLUDE_DIRS")
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "raycache_add_glsl_shader: unknown arguments: ${arg_UNPARSED_ARGUMENTS}")
  endif()
  foreach(_req TARGET SOURCE OUTPUT)
    if(NOT arg_${_req})
      message(FATAL_ERROR "raycache_add_glsl_shader: ${_req} is required")
    endif()
  endforeach()
  if(NOT TARGET ${arg_TARGET})
    message(FATAL_ERROR "raycache_add_glsl_shader: '${arg_TARGET}' is not a target")
  endif()

  find_program(RAYCACHE_GLSLANG_VALIDATOR NAMES glslangValidator
               HINTS "$ENV{VULKAN_SDK}/bin" DOC "glslangValidator used by raycache_add_glsl_shader")
  if(NOT RAYCACHE_GLSLANG_VALIDATOR)
    message(FATAL_ERROR "raycache_add_glsl_shader: glslangValidator not found. On Debian/Ubuntu: "
                        "apt-get install glslang-tools (or set RAYCACHE_GLSLANG_VALIDATOR=/path/to/it).")
  endif()

  set(_inc "")
  if(TARGET RayCache::GLSL)
    get_target_property(_inc RayCache::GLSL INTERFACE_RAYCACHE_GLSL_INCLUDE_DIR)
  endif()
  if(NOT _inc)
    set(_inc "${RayCache_GLSL_INCLUDE_DIR}")
  endif()
  if(NOT _inc OR NOT IS_DIRECTORY "${_inc}")
    message(FATAL_ERROR "raycache_add_glsl_shader: RayCache GLSL include directory not known "
                        "('${_inc}'); call find_package(RayCache COMPONENTS GLSL) or "
                        "add_subdirectory(<RayCache>) first.")
  endif()

  get_filename_component(_src "${arg_SOURCE}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  get_filename_component(_out "${arg_OUTPUT}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  get_filename_component(_out_dir "${_out}" DIRECTORY)

  set(_args --target-env vulkan1.1)
  if(arg_STAGE)
    if(arg_STAGE MATCHES "^(rgen|rint|rahit|rchit|rmiss|rcall)$")
      list(APPEND _args --target-env spirv1.4)
    endif()
    list(APPEND _args -S ${arg_STAGE})
  elseif(_src MATCHES "\\.(rgen|rint|rahit|rchit|rmiss|rcall)$")
    list(APPEND _args --target-env spirv1.4)
  endif()
  list(APPEND _args "-I${_inc}")
  foreach(_d IN LISTS arg_INCLUDE_DIRS)
    get_filename_component(_d "${_d}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    list(APPEND _args "-I${_d}")
  endforeach()
  foreach(_d IN LISTS arg_DEFINES)
    list(APPEND _args "-D${_d}")
  endforeach()

  # Rerun when any RayCache GLSL include changes (build tree: the staged list; installed: a glob).
  set(_deps ${RAYCACHE_GLSL_INCLUDE_FILES})
  if(NOT _deps)
    file(GLOB_RECURSE _deps "${_inc}/*.glsl" "${_inc}/*.h")
  endif()

  file(RELATIVE_PATH _rel "${CMAKE_BINARY_DIR}" "${_out}")
  add_custom_command(
    OUTPUT "${_out}"
    COMMAND "${CMAKE_COMMAND}" -E make_directory "${_out_dir}"
    COMMAND "${RAYCACHE_GLSLANG_VALIDATOR}" ${_args} -o "${_out}" "${_src}"
    DEPENDS "${_src}" ${_deps}
    COMMENT "GLSL -> SPIR-V ${_rel}"
    VERBATIM)

  string(MAKE_C_IDENTIFIER "${arg_TARGET}_spv_${_rel}" _custom)
  if(TARGET ${_custom})
    string(MD5 _hash "${_out}")
    string(SUBSTRING "${_hash}" 0 8 _hash)
    set(_custom "${_custom}_${_hash}")
  endif()
  add_custom_target(${_custom} DEPENDS "${_out}")
  add_dependencies(${arg_TARGET} ${_custom})
endfunction()
