# The part both consumer projects share, once RayCache is in (by find_package or add_subdirectory):
# 3. link one target (C++17 and glm come with it); 4. compile a shader that includes a shared header.
add_executable(raycache_consumer "${CMAKE_CURRENT_LIST_DIR}/consumer_main.cpp")
target_link_libraries(raycache_consumer PRIVATE RayCache::RayCache)
target_compile_definitions(raycache_consumer PRIVATE RAYCACHE_EXPECTED_VERSION="${RayCache_VERSION}")

find_program(GLSLANG_VALIDATOR glslangValidator)
if(GLSLANG_VALIDATOR)
  raycache_add_glsl_shader(TARGET raycache_consumer SOURCE "${CMAKE_CURRENT_LIST_DIR}/consumer_shader.comp"
                           OUTPUT shader.spv)
endif()

enable_testing()
add_test(NAME raycache_consumer COMMAND raycache_consumer)
