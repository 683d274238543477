#version 450
// Compiles only if the RayCache GLSL include directory provides raycache/shared/.
#extension GL_GOOGLE_include_directive : require
#include "raycache/shared/language.h"

layout(local_size_x = 1) in;
layout(std430, binding = 0) buffer Result { uint result; };

void main() { result = 1u; }
