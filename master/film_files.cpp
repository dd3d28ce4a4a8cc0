#include "film_files.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "farm/error.h"
#include "farm/hash.h"

namespace pf::master {

namespace fs = std::filesystem;

namespace {

// The trailer: a tag, then the payload's XXH3-64 in hex (farm/hash.h), at the very end of the file.
constexpr std::string_view kTag = "\npathfarm-xxh3:";
constexpr size_t kTrailerBytes = kTag.size() + 16;

[[noreturn]] void storageFailure(const std::string &what, const std::string &path, int err) {
    throw StorageError(what + " " + path + ": " + std::strerror(err));
}

// Writes everything or throws (the descriptor is closed and the file removed).
void writeAll(int fd, const std::string &path, std::string_view data) {
    for (size_t done = 0; done < data.size();) {
        const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            const int err = n < 0 ? errno : ENOSPC;
            ::close(fd);
            ::unlink(path.c_str());
            storageFailure("cannot write", path, err);
        }
        done += static_cast<size_t>(n);
    }
}

}  // namespace

void writeFilmFile(const std::string &path, std::string_view data, bool durable) {
    const std::string tmp = path + ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) storageFailure("cannot create", tmp, errno);
    writeAll(fd, tmp, data);
    writeAll(fd, tmp, std::string(kTag) + farm::hashHex64(data));
    // A full disk may only show at fsync or close (delayed allocation); the descriptor is closed either way.
    const bool synced = !durable || ::fsync(fd) == 0;
    const int syncError = errno;
    const bool closed = ::close(fd) == 0;
    if (!synced || !closed) {
        const int err = synced ? errno : syncError;
        ::unlink(tmp.c_str());
        storageFailure("cannot write", tmp, err);
    }
    if (::rename(tmp.c_str(), path.c_str()) != 0) {
        const int err = errno;
        ::unlink(tmp.c_str());
        storageFailure("cannot rename to", path, err);
    }
}

std::string readFilmFile(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw farm::FarmError("cannot read " + path + ": " + std::strerror(errno));
    std::ostringstream s;
    s << in.rdbuf();
    if (in.bad()) throw farm::FarmError("cannot read " + path);
    std::string data = std::move(s).str();
    if (data.size() < kTrailerBytes || std::string_view(data).substr(data.size() - kTrailerBytes, kTag.size()) != kTag)
        throw farm::FarmError(path + " is truncated (its checksum trailer is missing)");
    const std::string stored = data.substr(data.size() - 16);
    data.resize(data.size() - kTrailerBytes);
    if (farm::hashHex64(data) != stored) throw farm::FarmError(path + " fails its checksum");
    return data;
}

void checkWritable(const std::string &dir) {
    const std::string probe = (fs::path(dir) / ".write-probe").string();
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0) storageFailure("data directory is not writable: cannot create", probe, errno);
    // One block, so that a full file system shows now and not at the first result.
    writeAll(fd, probe, std::string(4096, '\0'));
    const bool synced = ::fsync(fd) == 0;
    const int err = errno;
    ::close(fd);
    ::unlink(probe.c_str());
    if (!synced) storageFailure("data directory is not writable: cannot write", probe, err);
}

}  // namespace pf::master
