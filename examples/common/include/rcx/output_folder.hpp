// rcx/output_folder.hpp: making sure the tracers can write their PNGs (and cache files) before they render.
#pragma once

#include <string>

namespace rcx {

// Creates `path` (and parents) when missing and checks a file can be written there.
// Throws std::runtime_error with the path and the reason otherwise.
void ensure_writable_directory(const std::string& path);

} // namespace rcx
