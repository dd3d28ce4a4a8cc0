#include "cpu_quota.h"

#include <sched.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace pf::worker {

namespace fs = std::filesystem;

namespace {

// One mounted cgroup hierarchy: the group at `root` of the hierarchy appears at `mountPoint`.
struct CgroupMount {
    std::string root;
    fs::path mountPoint;
};

std::vector<std::string> split(const std::string &s, char sep) {
    std::vector<std::string> parts;
    std::stringstream in(s);
    for (std::string part; std::getline(in, part, sep);) parts.push_back(part);
    return parts;
}

bool hasToken(const std::string &list, const std::string &token) {
    const auto parts = split(list, ',');
    return std::find(parts.begin(), parts.end(), token) != parts.end();
}

// mountinfo escapes space, tab, newline and backslash in paths as three octal digits (proc(5)).
std::string unescapeOctal(const std::string &s) {
    const auto octal = [](char c) { return c >= '0' && c <= '7'; };
    std::string out;
    for (size_t i = 0; i < s.size(); ++i) {
        if (s[i] == '\\' && i + 3 < s.size() && octal(s[i + 1]) && octal(s[i + 2]) && octal(s[i + 3])) {
            out += static_cast<char>((s[i + 1] - '0') * 64 + (s[i + 2] - '0') * 8 + (s[i + 3] - '0'));
            i += 3;
        } else {
            out += s[i];
        }
    }
    return out;
}

// The cgroup v2 mount (`v2`) or the v1 mount carrying the cpu controller, from mountinfo (proc(5)):
// "id parent major:minor root mountpoint options [optional...] - fstype source superoptions".
std::optional<CgroupMount> findMount(const fs::path &mountinfo, bool v2) {
    std::ifstream in(mountinfo);
    for (std::string line; std::getline(in, line);) {
        std::vector<std::string> f;
        std::istringstream words(line);
        for (std::string w; words >> w;) f.push_back(w);
        const auto dash = std::find(f.begin(), f.end(), "-");
        if (dash - f.begin() < 6 || f.end() - dash < 4) continue;
        const std::string &fstype = dash[1], &superOptions = dash[3];
        const bool match = v2 ? fstype == "cgroup2" : fstype == "cgroup" && hasToken(superOptions, "cpu");
        if (match) return CgroupMount{unescapeOctal(f[3]), unescapeOctal(f[4])};
    }
    return std::nullopt;
}

// This process's group in the v2 hierarchy ("0::/path") or in the v1 hierarchy with the cpu controller
// ("N:cpu,cpuacct:/path"), from /proc/self/cgroup (cgroups(7)).
std::optional<std::string> findGroup(const fs::path &cgroup, bool v2) {
    std::ifstream in(cgroup);
    for (std::string line; std::getline(in, line);) {
        const size_t a = line.find(':'), b = a == std::string::npos ? a : line.find(':', a + 1);
        if (b == std::string::npos) continue;
        const std::string id = line.substr(0, a), controllers = line.substr(a + 1, b - a - 1);
        const bool match = v2 ? id == "0" && controllers.empty() : hasToken(controllers, "cpu");
        if (match) return line.substr(b + 1);
    }
    return std::nullopt;
}

// The limit written in one group's directory, in CPUs; nullopt for "no limit" or an unreadable file.
std::optional<double> groupLimit(const fs::path &dir, bool v2) {
    double quota = -1, period = 0;
    if (v2) {
        // cpu.max: "$MAX $PERIOD", $MAX being "max" when unlimited (Documentation/admin-guide/cgroup-v2.rst).
        std::ifstream in(dir / "cpu.max");
        std::string max;
        if (!(in >> max >> period) || max == "max") return std::nullopt;
        std::istringstream(max) >> quota;
    } else {
        // cfs_quota_us is -1 when unlimited (Documentation/scheduler/sched-bwc.rst).
        std::ifstream q(dir / "cpu.cfs_quota_us"), p(dir / "cpu.cfs_period_us");
        if (!(q >> quota) || !(p >> period)) return std::nullopt;
    }
    if (quota <= 0 || period <= 0) return std::nullopt;
    return quota / period;
}

// The tightest limit from the group's directory up to the mount point.
std::optional<double> hierarchyLimit(const CgroupSources &src, bool v2) {
    const auto mount = findMount(src.mountinfo, v2);
    const auto group = findGroup(src.cgroup, v2);
    if (!mount || !group) return std::nullopt;
    // Inside a cgroup namespace (containers) the group path is relative to the namespace root, which is
    // also the mount's root ("/"); a bind-mounted subtree shows its own root instead. A group outside the
    // mount's subtree cannot be reached: then the mount point's own group is the closest visible one.
    fs::path dir = mount->mountPoint;
    if (mount->root == "/")
        dir /= fs::path(*group).relative_path();
    else if (group->rfind(mount->root, 0) == 0 &&
             (group->size() == mount->root.size() || (*group)[mount->root.size()] == '/'))
        dir /= fs::path(group->substr(mount->root.size())).relative_path();
    dir = dir.lexically_normal();
    if (!dir.has_filename()) dir = dir.parent_path();

    std::optional<double> tightest;
    for (;;) {
        if (const auto limit = groupLimit(dir, v2)) tightest = std::min(tightest.value_or(*limit), *limit);
        if (dir == mount->mountPoint.lexically_normal() || !dir.has_relative_path()) break;
        dir = dir.parent_path();
    }
    return tightest;
}

}  // namespace

std::optional<double> cgroupCpuLimit(const CgroupSources &sources) {
    const auto v2 = hierarchyLimit(sources, true), v1 = hierarchyLimit(sources, false);
    if (v2 && v1) return std::min(*v2, *v1);
    return v2 ? v2 : v1;
}

int coresWithinLimit(int affinityCores, std::optional<double> limit) {
    int cores = std::max(1, affinityCores);
    // A small tolerance keeps an exact quota such as 200000/100000 from rounding up through float error.
    if (limit) cores = std::min(cores, static_cast<int>(std::ceil(*limit - 1e-9)));
    return std::max(1, cores);
}

int availableCores() {
    cpu_set_t set;
    int cores = sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set) : 0;
    if (cores <= 0) cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    return coresWithinLimit(cores, cgroupCpuLimit());
}

}  // namespace pf::worker
