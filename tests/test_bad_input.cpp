// The bad-input corpus: every tests/bad_scenes/*.xml is a small scene with exactly one defect and, on
// its first line, the error it must produce: <!-- expect: line N: message substring -->. Loading it
// must throw a SceneError naming the file, that line and the substring, with or without --strict; the
// CLI must exit with code 2 and print the same. Input that Mitsuba 0.6 accepts with a warning (unused
// parameters) is in tests/warning_scenes, tested by test_bad_input_warnings.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <regex>

#include "scene/scene.h"
#include "support/process.h"
#include "support/render_util.h"

namespace pf {
namespace {

namespace fs = std::filesystem;

const std::string kCorpusDir = std::string(PATHFARM_SOURCE_DIR) + "/tests/bad_scenes";

struct Expectation {
    std::string file;  // file name, as it must appear in the message
    int line = 0;
    std::string substring;
};

std::vector<std::string> corpusFiles() {
    std::vector<std::string> files;
    for (const auto &entry : fs::directory_iterator(kCorpusDir))
        if (entry.path().extension() == ".xml") files.push_back(entry.path().string());
    std::sort(files.begin(), files.end());
    return files;
}

// Reads the expectation comment on a corpus file's first line; an empty substring means it is missing.
Expectation readExpectation(const std::string &path) {
    std::ifstream in(path);
    std::string first;
    std::getline(in, first);
    static const std::regex re(R"(^<!-- expect: line (\d+): (.+) -->$)");
    std::smatch m;
    Expectation e{fs::path(path).filename().string(), 0, ""};
    if (std::regex_match(first, m, re)) {
        e.line = std::stoi(m[1]);
        e.substring = m[2];
    }
    return e;
}

// Checks one error message against the expectation; returns "" if it matches.
std::string mismatch(const Expectation &e, const std::string &message) {
    const std::string where = e.file + ":" + std::to_string(e.line) + ":";
    if (message.find(where) == std::string::npos) return "message does not name " + where;
    if (message.find(e.substring) == std::string::npos) return "message lacks '" + e.substring + "'";
    return "";
}

std::string testName(const ::testing::TestParamInfo<std::string> &info) {
    std::string name = fs::path(info.param).stem().string();
    for (char &c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return name;
}

TEST(BadInputCorpus, IsLargeAndEveryFileStatesItsExpectation) {
    const auto files = corpusFiles();
    EXPECT_GE(files.size(), 24u);
    for (const auto &f : files) {
        const Expectation e = readExpectation(f);
        EXPECT_GT(e.line, 0) << f << ": first line must be <!-- expect: line N: substring -->";
        EXPECT_FALSE(e.substring.empty()) << f;
    }
}

class BadScene : public ::testing::TestWithParam<std::string> {};

TEST_P(BadScene, LoaderThrowsSceneErrorNamingFileAndLine) {
    const Expectation e = readExpectation(GetParam());
    ASSERT_GT(e.line, 0) << "no expectation comment";
    // Every defect here is an error with or without --strict (unused parameters, which only --strict
    // refuses, are tested in test_bad_input_warnings.cpp).
    for (const bool strict : {false, true}) {
        try {
            loadScene(GetParam(), {}, strict);
            ADD_FAILURE() << "loaded without error (strict " << strict << "); expected line " << e.line << ": "
                          << e.substring;
        } catch (const SceneError &err) {
            EXPECT_EQ(mismatch(e, err.what()), "") << "strict " << strict << ", got: " << err.what();
        }
    }
}

TEST_P(BadScene, CliExitsWithCode2AndPrintsTheError) {
    const std::string cli = test::cliPath();
    if (cli.empty()) GTEST_SKIP() << "PATHFARM_CLI is not set (run the tests through ctest to check the CLI)";
    const Expectation e = readExpectation(GetParam());
    ASSERT_GT(e.line, 0) << "no expectation comment";
    const std::string out = test::tempDir("bad_input_" + fs::path(GetParam()).stem().string()) + "/out.exr";
    const auto r = test::runCommand(cli + " render '" + GetParam() + "' --spp 1 -o '" + out + "'");
    EXPECT_EQ(r.exitCode, kExitBadInput) << r.output;
    EXPECT_EQ(mismatch(e, r.output), "") << "got: " << r.output;
    EXPECT_FALSE(fs::exists(out)) << "no image may be written for a bad scene";
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadScene, ::testing::ValuesIn(corpusFiles()), testName);

}  // namespace
}  // namespace pf
