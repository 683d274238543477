// Every public header, as a Makefile tracer includes them: with plain -I (not CMake's -isystem, which hides
// a library's warnings from its users), compiled by the test below with -Wall -Wextra -Wshadow -Wpedantic
// -Werror. RAYCACHE_WITH_EMBREE adds the Embree adapter.
#include <raycache/raycache.hpp>
#ifdef RAYCACHE_WITH_EMBREE
#include <raycache/embree/scene_cache.hpp>
#endif

int main() { return 0; }
