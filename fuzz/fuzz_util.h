// Shared by the libFuzzer targets (issue 18): a private directory per fuzzing process, into which a
// target writes the input as the file its reader expects (the readers take paths, as the loader and the
// farm call them).
#pragma once
#include <google/protobuf/message_lite.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

namespace pf::fuzz {

inline const std::string &workDir() {
    static const std::string dir = [] {
        const auto d = std::filesystem::temp_directory_path() / ("pathfarm-fuzz-" + std::to_string(::getpid()));
        std::filesystem::create_directories(d);
        return d.string();
    }();
    return dir;
}

// Writes `data` to workDir()/name and returns the path.
inline std::string writeInput(const std::string &name, const uint8_t *data, size_t size) {
    const std::string path = workDir() + "/" + name;
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char *>(data), static_cast<std::streamsize>(size));
    return path;
}

// A message as the stream targets read them: 2 bytes of length (little-endian), then the message.
inline std::string frame(const google::protobuf::MessageLite &m) {
    const std::string bytes = m.SerializeAsString();
    return std::string{static_cast<char>(bytes.size() & 0xff), static_cast<char>(bytes.size() >> 8)} + bytes;
}

// Reads the messages of a stream target's input one by one (see frame()), as a gRPC reader hands them
// to a service: false at the end, or at a message that does not parse (gRPC would end the call there).
class FrameReader {
public:
    FrameReader(const uint8_t *data, size_t size) : data_(data), size_(size) {}
    bool operator()(google::protobuf::MessageLite &m) {
        if (at_ + 2 > size_) return false;
        const size_t n = std::min<size_t>(data_[at_] | data_[at_ + 1] << 8, size_ - at_ - 2);
        m.Clear();
        const bool ok = m.ParseFromArray(data_ + at_ + 2, static_cast<int>(n));
        at_ += 2 + n;
        return ok;
    }

private:
    const uint8_t *data_;
    size_t size_, at_ = 0;
};

// Seeds that only the real encoders can make (scripts/fuzz.sh runs each target once with
// PATHFARM_FUZZ_SEEDS=DIR): written to DIR, and the process exits. Called from LLVMFuzzerInitialize.
inline void writeSeedsIfAsked(const std::function<std::vector<std::string>()> &make) {
    const char *dir = std::getenv("PATHFARM_FUZZ_SEEDS");
    if (!dir) return;
    std::filesystem::create_directories(dir);
    int n = 0;
    for (const std::string &seed : make())
        std::ofstream(std::string(dir) + "/encoded-" + std::to_string(n++), std::ios::binary) << seed;
    std::exit(0);
}

}  // namespace pf::fuzz

// Defines the target's LLVMFuzzerInitialize: writes the seeds `make` returns when asked.
#define PATHFARM_FUZZ_SEEDS(make)                          \
    extern "C" int LLVMFuzzerInitialize(int *, char ***) { \
        pf::fuzz::writeSeedsIfAsked(make);                 \
        return 0;                                          \
    }
