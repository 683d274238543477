// A RayCache consumer (installed or vendored): succeeds only if the headers match the package version.
#include <raycache/raycache.hpp>

#include <cstdio>
#include <string>

int main() {
    const std::string headers = raycache::version_string();
    std::printf("raycache headers %s, package %s\n", headers.c_str(), RAYCACHE_EXPECTED_VERSION);
    return headers == RAYCACHE_EXPECTED_VERSION ? 0 : 1;
}
