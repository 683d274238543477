# compile_glsl.cmake: the `glsl` test. Every GLSL file of RayCache's include (glsl_include/raycache/*.glsl
# and shared/*.h there) must compile on its own with glslangValidator, as a compute, fragment and
# ray-generation shader, and with its options (RAYCACHE_READ_ONLY in a fragment shader, where lookups
# without stores are the usual case; RAYCACHE_END_FRAME in a compute shader, where the end-frame pass
# runs); so must a shader that calls every public function (USE_ALL). Each module must pass spirv-val.
#
# cmake -DGLSLANG=<glslangValidator> [-DSPIRV_VAL=<spirv-val>] -DGLSL_DIR=<glsl_include/raycache>
#       -DINCLUDE_DIRS=<dir|dir...> -DUSE_ALL=<use_all.glsl> -DWORK_DIR=<dir> -P compile_glsl.cmake
foreach(_v GLSLANG GLSL_DIR INCLUDE_DIRS USE_ALL WORK_DIR)
  if(NOT DEFINED ${_v})
    message(FATAL_ERROR "compile_glsl.cmake: -D${_v}= is required")
  endif()
endforeach()
string(REPLACE "|" ";" _include_dirs "${INCLUDE_DIRS}")
set(_includes "")
foreach(_d IN LISTS _include_dirs)
  list(APPEND _includes "-I${_d}")
endforeach()

file(GLOB _files RELATIVE "${GLSL_DIR}" "${GLSL_DIR}/*.glsl" "${GLSL_DIR}/shared/*.h")
list(SORT _files)
if(NOT _files)
  message(FATAL_ERROR "compile_glsl.cmake: no GLSL files in ${GLSL_DIR}")
endif()
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
# The wrappers include it by a path relative to themselves.
configure_file("${USE_ALL}" "${WORK_DIR}/use_all.glsl" COPYONLY)

set(_failures 0)
set(_compiled 0)
# compile(<name> <stage> <body>): writes a wrapper shader and compiles and validates it.
function(compile name stage body)
  set(_version 450)
  set(_head "")
  set(_env --target-env vulkan1.1)
  if(stage STREQUAL "rgen")
    set(_version 460)
    set(_head "#extension GL_EXT_ray_tracing : require\n")
    list(APPEND _env --target-env spirv1.4)
  elseif(stage STREQUAL "comp")
    set(_head "layout(local_size_x = 1) in;\n")
  endif()
  set(_src "${WORK_DIR}/${name}.${stage}")
  file(WRITE "${_src}" "#version ${_version}\n#extension GL_GOOGLE_include_directive : require\n${_head}${body}")
  execute_process(COMMAND "${GLSLANG}" ${_env} -S ${stage} ${_includes} -o "${_src}.spv" "${_src}"
                  RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
  if(_rc EQUAL 0 AND SPIRV_VAL)
    set(_val_env vulkan1.1)
    if(stage STREQUAL "rgen")
      set(_val_env vulkan1.1spv1.4)
    endif()
    execute_process(COMMAND "${SPIRV_VAL}" --target-env ${_val_env} "${_src}.spv"
                    RESULT_VARIABLE _rc OUTPUT_VARIABLE _val ERROR_VARIABLE _val)
    string(APPEND _out "${_val}")
  endif()
  math(EXPR _n "${_compiled} + 1")
  set(_compiled ${_n} PARENT_SCOPE)
  if(NOT _rc EQUAL 0)
    message("FAILED: ${name} as ${stage} (${_src}):\n${_out}")
    math(EXPR _n "${_failures} + 1")
    set(_failures ${_n} PARENT_SCOPE)
  endif()
endfunction()

# Option set and the stages it is compiled for.
# Several options join with "+".
set(_variants "default:comp;default:frag;default:rgen;RAYCACHE_READ_ONLY:frag;RAYCACHE_END_FRAME:comp"
              "RAYCACHE_CONFIDENCE:frag;RAYCACHE_CONFIDENCE+RAYCACHE_READ_ONLY:frag;RAYCACHE_CONFIDENCE+RAYCACHE_END_FRAME:comp"
              "RAYCACHE_ORIGINS:comp;RAYCACHE_ORIGINS+RAYCACHE_READ_ONLY:frag;RAYCACHE_ORIGINS+RAYCACHE_END_FRAME:comp"
              "RAYCACHE_ORIGINS+RAYCACHE_CONFIDENCE+RAYCACHE_END_FRAME:comp")
foreach(_file IN LISTS _files ITEMS use_all.glsl)
  string(MAKE_C_IDENTIFIER "${_file}" _id)
  foreach(_variant IN LISTS _variants)
    string(REPLACE ":" ";" _variant "${_variant}")
    list(GET _variant 0 _option)
    list(GET _variant 1 _stage)
    set(_define "")
    if(NOT _option STREQUAL "default")
      string(REPLACE "+" ";" _options "${_option}")
      foreach(_o IN LISTS _options)
        string(APPEND _define "#define ${_o}\n")
      endforeach()
      string(REPLACE "+" "_" _option "${_option}")
    endif()
    if(_file STREQUAL "use_all.glsl")
      compile("${_id}_${_option}" ${_stage} "${_define}#include \"use_all.glsl\"\nvoid main() { raycache_test_use_all(); }\n")
    else()
      compile("${_id}_${_option}" ${_stage} "${_define}#include \"raycache/${_file}\"\nvoid main() {}\n")
    endif()
  endforeach()
endforeach()

list(LENGTH _files _count)
if(SPIRV_VAL)
  set(_validated "compiled and validated by spirv-val")
else()
  set(_validated "compiled (spirv-val not found: not validated)")
endif()
message("glsl: ${_count} files (${_files}); ${_compiled} shaders ${_validated}, ${_failures} failed")
if(_failures GREATER 0)
  message(FATAL_ERROR "glsl: ${_failures} of ${_compiled} shaders failed to compile or validate")
endif()
