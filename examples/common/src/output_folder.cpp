// The output folder check (rcx/output_folder.hpp).
#include "rcx/output_folder.hpp"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>
#ifdef __linux__
#include <linux/magic.h>
#include <sys/vfs.h>
#endif

namespace rcx {

namespace {

// Why a file or folder could not be created in the existing folder `folder` (errno `error`), in words a
// user can act on: the system's message alone misleads on virtual file systems, where creating a file in
// a folder that exists fails with "No such file or directory".
std::string why_nothing_can_be_created(const std::string& folder, int error) {
    const std::string system = std::strerror(error);
#ifdef __linux__
    struct statfs fs{};
    if (statfs(folder.c_str(), &fs) == 0) {
        const char* kind = nullptr;
        switch (static_cast<unsigned long>(fs.f_type)) {
        case PROC_SUPER_MAGIC: kind = "proc"; break;
        case SYSFS_MAGIC: kind = "sysfs"; break;
        case DEBUGFS_MAGIC: kind = "debugfs"; break;
        case TRACEFS_MAGIC: kind = "tracefs"; break;
        case CGROUP_SUPER_MAGIC: case CGROUP2_SUPER_MAGIC: kind = "cgroup"; break;
        default: break;
        }
        if (kind)
            return "'" + folder + "' is on the kernel's " + kind +
                   " file system, which only shows kernel state: no files can be created there (the system says: " +
                   system + ")";
    }
#endif
    switch (error) {
    case EACCES:
    case EPERM: return "no permission to create files in '" + folder + "' (" + system + ")";
    case EROFS: return "'" + folder + "' is on a read-only file system";
    case ENOSPC: return "the file system of '" + folder + "' is full";
    case EDQUOT: return "the disk quota for '" + folder + "' is used up";
    case ENOENT: return "the file system of '" + folder + "' does not let files be created there (" + system + ")";
    default: return "creating a file in '" + folder + "' failed: " + system;
    }
}

// The nearest folder that exists on the way to `path` (`path` itself when it exists).
std::filesystem::path nearest_existing(std::filesystem::path path) {
    std::error_code ec;
    path = std::filesystem::absolute(path, ec);
    while (!path.empty() && !std::filesystem::exists(path, ec) && path.has_relative_path()) path = path.parent_path();
    return path;
}

} // namespace

void ensure_writable_directory(const std::string& path, const std::string& option) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::exists(path, ec) && !fs::is_directory(path, ec))
        throw std::runtime_error("output folder '" + path + "' is a file, not a folder; choose another " + option);
    fs::create_directories(path, ec);
    if (ec) {
        const fs::path parent = nearest_existing(path);
        throw std::runtime_error("cannot create output folder '" + path + "': " +
                                 (fs::is_directory(parent) ? why_nothing_can_be_created(parent.string(), ec.value())
                                                           : ec.message()) +
                                 "; choose another " + option);
    }
    // Probe with a real file: permissions alone do not tell (read-only mounts, ACLs, root, virtual file systems).
    const fs::path probe = fs::path(path) / (".rcx-write-test-" + std::to_string(
        std::chrono::steady_clock::now().time_since_epoch().count()));
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0)
        throw std::runtime_error("cannot write into output folder '" + path + "': " + why_nothing_can_be_created(path, errno) +
                                 "; choose another " + option);
    const bool written = ::write(fd, "x", 1) == 1;
    const int write_error = errno;
    ::close(fd);
    fs::remove(probe, ec);
    if (!written)
        throw std::runtime_error("cannot write into output folder '" + path + "': " +
                                 why_nothing_can_be_created(path, write_error) + "; choose another " + option);
}

void ensure_writable_folder_of(const std::string& path) {
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    ensure_writable_directory(folder.empty() ? "." : folder.string(), "--save-cache");
}

} // namespace rcx
