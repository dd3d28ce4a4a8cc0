// What the Markov-chain benchmarks share: loading a shared scene with another sampleCount (the seeds per
// pixel of ERPT-type bursts, which take their budget from the scene) at a square benchmark resolution.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>

#include "scene/scene.h"

namespace bench {

// The scene at res x res with its sensor's sampleCount set to `spp`, through a rewritten copy of the file
// beside links to the scene's other files (in a per-process temporary directory named after `tag`).
inline std::unique_ptr<pf::Scene> loadWithSampleCount(const std::string &path, int spp, int res,
                                                      const std::string &tag) {
    namespace fs = std::filesystem;
    const fs::path src(path);
    const fs::path dir =
        fs::temp_directory_path() / (tag + "_" + std::to_string(getpid())) / src.parent_path().filename();
    fs::create_directories(dir);
    for (const auto &entry : fs::directory_iterator(src.parent_path()))
        if (entry.path().filename() != src.filename() && !fs::exists(dir / entry.path().filename()))
            fs::create_symlink(fs::absolute(entry.path()), dir / entry.path().filename());
    std::ifstream in(src);
    std::stringstream xml;
    xml << in.rdbuf();
    const std::regex count(R"(<integer name="sampleCount" value="[^"]*"\s*/>)");
    std::ofstream(dir / "scene.xml") << std::regex_replace(
        xml.str(), count, "<integer name=\"sampleCount\" value=\"" + std::to_string(spp) + "\"/>");
    auto scene = pf::loadScene((dir / "scene.xml").string());
    scene->resizeFilm(res, res);
    return scene;
}

}  // namespace bench
