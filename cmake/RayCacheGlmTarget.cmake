# RayCacheGlmTarget.cmake: after find_package(glm), makes sure the target glm::glm exists, which
# RayCache::RayCache links. Older glm configs define only `glm`, or nothing but GLM_INCLUDE_DIRS.
# Included by the build and by the installed RayCacheConfig.cmake, so both see the same target.
if(NOT TARGET glm::glm)
  add_library(glm::glm INTERFACE IMPORTED)
  if(TARGET glm)
    target_link_libraries(glm::glm INTERFACE glm)
  else()
    target_include_directories(glm::glm INTERFACE ${GLM_INCLUDE_DIRS})
  endif()
endif()
