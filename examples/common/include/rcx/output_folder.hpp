// rcx/output_folder.hpp: making sure the tracers can write their PNGs (and cache files) before they render.
#pragma once

#include <string>

namespace rcx {

// Creates `path` (and parents) when missing and checks a file can be written there.
// Throws std::runtime_error with the path and the reason otherwise, telling to choose another `option`.
void ensure_writable_directory(const std::string& path, const std::string& option = "--out");

// ensure_writable_directory() of the folder that will hold the file `path` (the working directory for a
// bare name): a --save-cache folder that cannot take the file fails before the first frame, not after the
// last. Throws as it does.
void ensure_writable_folder_of(const std::string& path);

} // namespace rcx
