#include "farm/bundle.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <pugixml.hpp>
#include <set>

#include "farm/error.h"

namespace pf::farm {

namespace fs = std::filesystem;

namespace {

constexpr size_t kMaxEntries = 100000;
constexpr size_t kMaxPathLength = 4096;
constexpr int kMaxXmlDepth = 64;  // as the scene loader: bounds the walk on hostile input

bool isHex(std::string_view s, size_t length) {
    return s.size() == length &&
           std::all_of(s.begin(), s.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

// Relative, '/'-separated, every component a plain name: nothing that a join with the bundle's root
// could turn into a path outside it, on any platform.
std::string entryPathProblem(const std::string &p) {
    if (p.empty()) return "empty path";
    if (p.size() > kMaxPathLength) return "path too long";
    if (p.front() == '/') return "absolute path";
    if (p.find('\\') != std::string::npos) return "backslash in path";
    if (p.find('\0') != std::string::npos) return "NUL in path";
    size_t start = 0;
    for (bool first = true;; first = false) {
        const size_t slash = p.find('/', start);
        const std::string part = p.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
        if (part.empty()) return "empty path component";
        if (part == "..") return "'..' in path";
        if (part == ".") return "'.' in path";
        if (first && part.back() == ':') return "absolute path (drive letter)";
        if (slash == std::string::npos) return "";
        start = slash + 1;
    }
}

class SceneFileCollector {
public:
    SceneFileCollector(const fs::path &root, const NameValues &defines) : root_(root) {
        for (const auto &[name, value] : defines) params_[name] = value;
    }

    void collectFile(const fs::path &path) {
        const std::string rel = relative(path);
        if (rel.empty() || !seen_.insert(rel).second) return;
        files_.push_back(rel);
        pugi::xml_document doc;
        if (!doc.load_file(path.c_str())) return;  // the master's load reports the precise error
        walk(doc, path.parent_path(), 0);
    }

    std::vector<std::string> files() const { return files_; }

private:
    // Path relative to the root if `path` is an existing file inside it, else "".
    std::string relative(const fs::path &path) const {
        const fs::path rel = path.lexically_normal().lexically_relative(root_);
        std::error_code ec;
        if (rel.empty() || *rel.begin() == ".." || !fs::is_regular_file(path, ec)) return "";
        return rel.generic_string();
    }

    void candidate(const fs::path &dir, const std::string &name, bool isInclude) {
        if (name.empty() || fs::path(name).has_root_path()) return;
        const fs::path full = (dir / name).lexically_normal();
        if (isInclude) {
            collectFile(full);
        } else if (const std::string rel = relative(full); !rel.empty() && seen_.insert(rel).second) {
            files_.push_back(rel);
        }
    }

    // $name substitution as the loader does it (longest defined name wins); unmatched names stay, and
    // then simply name no file.
    std::string substitute(const std::string &raw) const {
        std::string out;
        for (size_t i = 0; i < raw.size(); ++i) {
            const std::string *best = nullptr;
            if (raw[i] == '$')
                for (const auto &[name, value] : params_)
                    if (raw.compare(i + 1, name.size(), name) == 0 && (!best || name.size() > best->size()))
                        best = &name;
            if (!best) {
                out += raw[i];
                continue;
            }
            out += params_.at(*best);
            i += best->size();
        }
        return out;
    }

    void walk(const pugi::xml_node &node, const fs::path &dir, int depth) {
        if (depth > kMaxXmlDepth) return;
        for (const pugi::xml_node &e : node.children()) {
            if (e.type() != pugi::node_element) continue;
            const std::string tag = e.name();
            // Command-line definitions take precedence over <default>, as in the loader.
            if (tag == "default") params_.emplace(e.attribute("name").value(), e.attribute("value").value());
            if (tag == "include" || tag == "spectrum")
                candidate(dir, substitute(e.attribute("filename").value()), tag == "include");
            if (tag == "string") candidate(dir, substitute(e.attribute("value").value()), false);
            walk(e, dir, depth + 1);
        }
    }

    fs::path root_;
    std::map<std::string, std::string> params_;
    std::set<std::string> seen_;
    std::vector<std::string> files_;
};

// Removes a directory tree on scope exit unless released.
class TreeGuard {
public:
    explicit TreeGuard(fs::path p) : path_(std::move(p)) {}
    ~TreeGuard() {
        std::error_code ec;
        if (!path_.empty()) fs::remove_all(path_, ec);
    }
    void release() { path_.clear(); }

private:
    fs::path path_;
};

// Writes the manifest's files one after the other as their bytes arrive, checking each file's size
// and hash when it is complete.
class EntryWriter {
public:
    EntryWriter(const BundleManifest &m, fs::path dir) : m_(m), dir_(std::move(dir)) { openNext(); }

    void write(std::string_view data) {
        while (!data.empty()) {
            if (index_ >= static_cast<size_t>(m_.entries_size()))
                throw FarmError("bundle: more data than the manifest lists");
            const auto &e = m_.entries(static_cast<int>(index_));
            const size_t n = static_cast<size_t>(std::min<uint64_t>(e.size() - written_, data.size()));
            out_.write(data.data(), static_cast<std::streamsize>(n));
            hasher_->update(data.substr(0, n));
            written_ += n;
            data.remove_prefix(n);
            if (written_ == e.size()) closeCurrent();
        }
    }

    void finish() {
        if (index_ < static_cast<size_t>(m_.entries_size()))
            throw FarmError("bundle: stream ended inside '" + m_.entries(static_cast<int>(index_)).path() + "'");
    }

private:
    void openNext() {
        if (index_ >= static_cast<size_t>(m_.entries_size())) return;
        const fs::path p = dir_ / m_.entries(static_cast<int>(index_)).path();
        fs::create_directories(p.parent_path());
        out_ = std::ofstream(p, std::ios::binary | std::ios::trunc);
        if (!out_) throw FarmError("bundle: cannot write " + p.string());
        hasher_ = std::make_unique<Hasher64>();
        written_ = 0;
        if (m_.entries(static_cast<int>(index_)).size() == 0) closeCurrent();
    }

    void closeCurrent() {
        const auto &e = m_.entries(static_cast<int>(index_));
        out_.close();
        if (!out_) throw FarmError("bundle: cannot write '" + e.path() + "'");
        if (hasher_->hex() != e.hash())
            throw FarmError("bundle: content of '" + e.path() + "' does not match its hash");
        ++index_;
        openNext();
    }

    const BundleManifest &m_;
    fs::path dir_;
    size_t index_ = 0;
    uint64_t written_ = 0;
    std::ofstream out_;
    std::unique_ptr<Hasher64> hasher_;
};

}  // namespace

std::vector<std::string> collectSceneFiles(const std::string &scenePath, const NameValues &defines) {
    const fs::path scene = fs::absolute(scenePath).lexically_normal();
    SceneFileCollector c(scene.parent_path(), defines);
    c.collectFile(scene);
    return c.files();
}

BundleManifest makeManifest(const std::string &rootDir, const std::string &sceneFile, std::vector<std::string> files) {
    std::sort(files.begin(), files.end());
    files.erase(std::unique(files.begin(), files.end()), files.end());
    BundleManifest m;
    m.set_scene_file(sceneFile);
    std::string buf(1 << 20, '\0');
    for (const std::string &f : files) {
        std::ifstream in(fs::path(rootDir) / f, std::ios::binary);
        if (!in) throw FarmError("cannot read " + (fs::path(rootDir) / f).string());
        Hasher64 h;
        uint64_t size = 0;
        while (in.read(buf.data(), static_cast<std::streamsize>(buf.size())) || in.gcount() > 0) {
            h.update(std::string_view(buf.data(), static_cast<size_t>(in.gcount())));
            size += static_cast<uint64_t>(in.gcount());
        }
        auto *e = m.add_entries();
        e->set_path(f);
        e->set_size(size);
        e->set_hash(h.hex());
    }
    return m;
}

std::string bundleHash(const BundleManifest &manifest) {
    std::vector<const pathfarm::v1::BundleEntry *> entries;
    for (const auto &e : manifest.entries()) entries.push_back(&e);
    std::sort(entries.begin(), entries.end(), [](auto *a, auto *b) { return a->path() < b->path(); });
    std::string canonical = "pathfarm-bundle-v1\n" + manifest.scene_file() + "\n";
    for (const auto *e : entries) canonical += e->path() + '\0' + std::to_string(e->size()) + '\0' + e->hash() + '\n';
    return hashHex128(canonical);
}

void validateManifest(const BundleManifest &manifest, uint64_t maxBytes) {
    if (manifest.entries_size() == 0) throw FarmError("bundle: no entries");
    if (static_cast<size_t>(manifest.entries_size()) > kMaxEntries)
        throw FarmError("bundle: more than " + std::to_string(kMaxEntries) + " entries");
    std::set<std::string> paths;
    uint64_t total = 0;
    for (const auto &e : manifest.entries()) {
        if (const std::string problem = entryPathProblem(e.path()); !problem.empty())
            throw FarmError("bundle entry '" + e.path() + "': " + problem +
                            " (bundles cannot reach outside themselves)");
        if (!paths.insert(e.path()).second) throw FarmError("bundle entry '" + e.path() + "' is listed twice");
        if (!isHex(e.hash(), 16)) throw FarmError("bundle entry '" + e.path() + "': malformed hash");
        total += e.size();
        if (e.size() > maxBytes || total > maxBytes)
            throw FarmError("bundle: larger than the limit of " + std::to_string(maxBytes) + " bytes");
    }
    if (!paths.count(manifest.scene_file()))
        throw FarmError("bundle: the scene file '" + manifest.scene_file() + "' is not one of its entries");
}

void streamBundle(const std::string &dir, const BundleManifest &manifest, size_t chunkBytes,
                  const std::function<bool(const BundleChunk &)> &emit) {
    BundleChunk chunk;
    *chunk.mutable_manifest() = manifest;
    if (!emit(chunk)) return;
    std::string buf;
    buf.reserve(chunkBytes);
    auto flush = [&]() {
        chunk.Clear();
        chunk.set_data(std::move(buf));
        buf.clear();
        return emit(chunk);
    };
    for (const auto &e : manifest.entries()) {
        std::ifstream in(fs::path(dir) / e.path(), std::ios::binary);
        if (!in) throw FarmError("bundle: cannot read '" + e.path() + "'");
        for (uint64_t left = e.size(); left > 0;) {
            const size_t n = static_cast<size_t>(std::min<uint64_t>(left, chunkBytes - buf.size()));
            const size_t old = buf.size();
            buf.resize(old + n);
            if (!in.read(buf.data() + old, static_cast<std::streamsize>(n)))
                throw FarmError("bundle: '" + e.path() + "' is shorter than its manifest entry");
            left -= n;
            if (buf.size() == chunkBytes && !flush()) return;
        }
    }
    if (!buf.empty()) flush();
}

BundleStore::BundleStore(std::string root, uint64_t maxBytes) : root_(std::move(root)), maxBytes_(maxBytes) {
    fs::create_directories(root_);
}

bool BundleStore::has(const std::string &hash) const {
    std::error_code ec;
    return isHex(hash, 32) && fs::exists(fs::path(root_) / (hash + ".manifest"), ec);
}

std::string BundleStore::dir(const std::string &hash) const {
    if (!isHex(hash, 32)) throw FarmError("malformed bundle hash '" + hash + "'");
    return (fs::path(root_) / hash).string();
}

BundleManifest BundleStore::manifest(const std::string &hash) const {
    std::ifstream in(dir(hash) + ".manifest", std::ios::binary);
    BundleManifest m;
    if (!in || !m.ParseFromIstream(&in)) throw FarmError("bundle " + hash + " is not stored");
    return m;
}

std::string BundleStore::receive(const std::function<bool(BundleChunk &)> &next, const std::string &expectedHash) {
    BundleChunk chunk;
    if (!next(chunk) || !chunk.has_manifest()) throw FarmError("bundle: the stream must start with the manifest");
    const BundleManifest manifest = chunk.manifest();
    validateManifest(manifest, maxBytes_);
    const std::string hash = bundleHash(manifest);
    if (!expectedHash.empty() && hash != expectedHash)
        throw FarmError("bundle: received " + hash + ", expected " + expectedHash);
    if (has(hash)) return hash;

    static std::atomic<uint64_t> counter{0};
    const fs::path tmp =
        fs::path(root_) / (".incoming-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" + hash);
    fs::create_directories(tmp);
    TreeGuard guard(tmp);
    EntryWriter writer(manifest, tmp / "files");
    while (next(chunk)) {
        if (!chunk.has_data()) throw FarmError("bundle: a second manifest in the stream");
        writer.write(chunk.data());
    }
    writer.finish();
    {
        std::ofstream out(tmp / "manifest", std::ios::binary);
        if (!manifest.SerializeToOstream(&out) || !out.flush()) throw FarmError("bundle: cannot store the manifest");
    }
    // Files first, then the manifest that makes the bundle visible. A directory without its manifest is
    // what a crash between the two renames leaves behind; a receiver of the same bundle that got there
    // first wins and this copy is dropped.
    const std::lock_guard<std::mutex> lock(publishMutex_);
    if (has(hash)) return hash;
    std::error_code ec;
    fs::remove_all(dir(hash), ec);
    fs::rename(tmp / "files", dir(hash), ec);
    if (!ec) fs::rename(tmp / "manifest", dir(hash) + ".manifest", ec);
    if (!has(hash)) throw FarmError("bundle: cannot store " + hash + ": " + ec.message());
    return hash;
}

}  // namespace pf::farm
