// The worker's default thread count under container CPU limits (worker/cpu_quota.h): fake
// /proc/self/mountinfo and /proc/self/cgroup files whose mount points lead into a fake cgroup tree, laid
// out as runc, systemd and Kubernetes lay out the real ones (cgroup v2, v1 and hybrid).
#include <gtest/gtest.h>
#include <sched.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <vector>

#include "cpu_quota.h"
#include "support/render_util.h"

namespace fs = std::filesystem;
using pf::worker::cgroupCpuLimit;
using pf::worker::CgroupSources;
using pf::worker::coresWithinLimit;

namespace {

class CpuQuota : public ::testing::Test {
protected:
    void SetUp() override {
        root_ = pf::test::tempDir(std::string("cpu_quota-") +
                                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
        src_.mountinfo = root_ / "mountinfo";
        src_.cgroup = root_ / "cgroup";
    }
    void TearDown() override { fs::remove_all(root_); }

    void write(const fs::path &path, const std::string &text) const {
        fs::create_directories(path.parent_path());
        std::ofstream(path) << text;
    }
    fs::path tree(const std::string &rel) const { return root_ / rel; }
    // `text` with every "@" replaced by the fake tree's root.
    std::string rooted(std::string text) const {
        for (size_t at; (at = text.find('@')) != std::string::npos;) text.replace(at, 1, root_.string());
        return text;
    }

    fs::path root_;
    CgroupSources src_;
};

const std::string kOtherMounts =
    "22 1 0:21 / /proc rw,nosuid - proc proc rw\n"
    "23 22 0:22 / /sys rw,nosuid - sysfs sysfs rw\n";

// One cgroup layout: the fake /proc/self/mountinfo and /proc/self/cgroup ("@" stands for the fake tree's
// root), the files of the tree, and the limit and thread count they must give.
struct Layout {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const Layout &c, std::ostream *os) { *os << c.name; }
    const char *name;
    std::string mountinfo, cgroup;
    std::vector<std::pair<std::string, std::string>> files;
    std::optional<double> limit;
    int affinityCores, threads;
};

// mountinfo lines as the kernel writes them: a cgroup2 mount and a v1 mount of `controllers`.
std::string v2Mount(const std::string &root, const std::string &dir) {
    return "30 23 0:26 " + root + " @/" + dir + " rw,nosuid,nodev,noexec,relatime shared:9 - cgroup2 cgroup2 rw\n";
}
std::string v1Mount(const std::string &dir, const std::string &controllers) {
    return "31 23 0:27 / @/" + dir + " rw,nosuid,nodev,noexec,relatime shared:10 - cgroup cgroup rw," + controllers +
           "\n";
}

const std::vector<Layout> kLayouts = {
    // cgroup v2 on a host (a systemd service): the group's own cpu.max, 1.5 CPUs, gives two threads.
    {"V2OwnGroup",
     kOtherMounts + v2Mount("/", "cg2"),
     "0::/system.slice/pathfarm-worker.service\n",
     {{"cg2/system.slice/pathfarm-worker.service/cpu.max", "150000 100000\n"},
      {"cg2/system.slice/cpu.max", "max 100000\n"}},
     1.5,
     16,
     2},
    // A Kubernetes pod: the pod's group carries the tighter limit and binds the container below it; an
    // exact limit does not round up to one more thread.
    {"V2AncestorIsTighter",
     v2Mount("/", "cg2"),
     "0::/kubepods.slice/pod1/ctr\n",
     {{"cg2/kubepods.slice/pod1/ctr/cpu.max", "400000 100000\n"},
      {"cg2/kubepods.slice/pod1/cpu.max", "300000 100000\n"},
      {"cg2/kubepods.slice/cpu.max", "max 100000\n"},
      {"cg2/cpu.max", "max 100000\n"}},
     3.0,
     16,
     3},
    // Inside a container with a cgroup namespace (runc, podman): the group is "/" and cpu.max sits at the
    // mount point itself.
    {"V2ContainerNamespace",
     v2Mount("/", "sys/fs/cgroup"),
     "0::/\n",
     {{"sys/fs/cgroup/cpu.max", "200000 100000\n"}},
     2.0,
     64,
     2},
    // A bind-mounted subtree (no cgroup namespace): the mount's root is the container's group, so the
    // path below it is taken relative to that root (taken whole, it would miss the container's own limit
    // and find the mount point's looser one); groups above the mount are invisible.
    {"V2BindMountedSubtree",
     v2Mount("/machine.slice/libpod-abc.scope", "sys/fs/cgroup"),
     "0::/machine.slice/libpod-abc.scope/container\n",
     {{"sys/fs/cgroup/container/cpu.max", "50000 100000\n"}, {"sys/fs/cgroup/cpu.max", "200000 100000\n"}},
     0.5,
     8,
     1},
    // No limit anywhere: every core of the affinity mask is used.
    {"V2Unlimited",
     v2Mount("/", "cg2"),
     "0::/user.slice\n",
     {{"cg2/user.slice/cpu.max", "max 100000\n"}},
     std::nullopt,
     8,
     8},
    // Hybrid mode (as on this project's machines): a cgroup2 mount without the cpu controller (no
    // cpu.max) beside v1 hierarchies, cpu co-mounted with cpuacct; a cpuset-only mount must not be taken
    // for the cpu controller.
    {"HybridV1CpuController",
     kOtherMounts + v1Mount("sys/fs/cgroup/cpu,cpuacct", "cpu,cpuacct") + v1Mount("sys/fs/cgroup/cpuset", "cpuset") +
         v2Mount("/", "sys/fs/cgroup/unified"),
     "4:cpuset:/docker/abc\n3:cpu,cpuacct:/docker/abc\n0::/docker/abc\n",
     {{"sys/fs/cgroup/cpu,cpuacct/docker/abc/cpu.cfs_quota_us", "250000\n"},
      {"sys/fs/cgroup/cpu,cpuacct/docker/abc/cpu.cfs_period_us", "100000\n"},
      {"sys/fs/cgroup/cpu,cpuacct/docker/cpu.cfs_quota_us", "-1\n"},
      {"sys/fs/cgroup/cpu,cpuacct/docker/cpu.cfs_period_us", "100000\n"},
      {"sys/fs/cgroup/cpuset/docker/abc/cpu.cfs_quota_us", "10000\n"},
      {"sys/fs/cgroup/cpuset/docker/abc/cpu.cfs_period_us", "100000\n"}},
     2.5,
     8,
     3},
    // v1 without a quota (cfs_quota_us = -1).
    {"V1Unlimited",
     v1Mount("cpu", "cpu"),
     "1:cpu:/\n",
     {{"cpu/cpu.cfs_quota_us", "-1\n"}, {"cpu/cpu.cfs_period_us", "100000\n"}},
     std::nullopt,
     4,
     4},
    // Both hierarchies limit: the tighter one applies.
    {"BothHierarchiesTakeTheTighter",
     v1Mount("v1cpu", "cpu") + v2Mount("/", "v2"),
     "1:cpu:/a\n0::/b\n",
     {{"v1cpu/a/cpu.cfs_quota_us", "300000\n"},
      {"v1cpu/a/cpu.cfs_period_us", "100000\n"},
      {"v2/b/cpu.max", "100000 50000\n"}},
     2.0,
     8,
     2},
    // mountinfo escapes a space in a mount point as \040 (proc(5)).
    {"EscapedMountPoint",
     v2Mount("/", "cgroup\\040fs"),
     "0::/job\n",
     {{"cgroup fs/job/cpu.max", "100000 100000\n"}},
     1.0,
     8,
     1},
};

class CgroupLayouts : public CpuQuota, public ::testing::WithParamInterface<Layout> {};

}  // namespace

TEST_P(CgroupLayouts, LimitAndThreads) {
    const Layout &l = GetParam();
    write(src_.mountinfo, rooted(l.mountinfo));
    write(src_.cgroup, l.cgroup);
    for (const auto &[path, text] : l.files) write(tree(path), text);
    const auto limit = cgroupCpuLimit(src_);
    ASSERT_EQ(limit.has_value(), l.limit.has_value());
    if (limit) {
        EXPECT_DOUBLE_EQ(*limit, *l.limit);
    }
    EXPECT_EQ(coresWithinLimit(l.affinityCores, limit), l.threads);
}

INSTANTIATE_TEST_SUITE_P(CpuQuota, CgroupLayouts, ::testing::ValuesIn(kLayouts),
                         [](const auto &info) { return std::string(info.param.name); });

// Missing or malformed files mean "no limit known", never a crash or a zero thread count.
TEST_F(CpuQuota, MissingOrMalformedFiles) {
    EXPECT_FALSE(cgroupCpuLimit(src_).has_value());  // neither file exists
    write(src_.mountinfo, rooted("garbage\n\n30 22 0:27 / x\n" + v2Mount("/", "cg2")));
    write(src_.cgroup, "no colons here\n0::/g\n");
    EXPECT_FALSE(cgroupCpuLimit(src_).has_value());  // no cpu.max
    write(tree("cg2/g/cpu.max"), "lots 100000\n");
    EXPECT_FALSE(cgroupCpuLimit(src_).has_value());
    write(tree("cg2/g/cpu.max"), "100000 0\n");
    EXPECT_FALSE(cgroupCpuLimit(src_).has_value());
    write(tree("cg2/g/cpu.max"), "100000\n");
    EXPECT_FALSE(cgroupCpuLimit(src_).has_value());
    EXPECT_EQ(coresWithinLimit(0, std::nullopt), 1);
}

TEST(CoresWithinLimit, Rounding) {
    EXPECT_EQ(coresWithinLimit(4, 0.01), 1);  // a tiny quota still gets one thread
    EXPECT_EQ(coresWithinLimit(4, 1.0), 1);
    EXPECT_EQ(coresWithinLimit(4, 1.0001), 2);
    EXPECT_EQ(coresWithinLimit(2, 8.0), 2);  // the limit never adds cores beyond the affinity mask
}

// On the machine running the test: the default never exceeds the affinity mask and respects whatever
// limit the real files state.
TEST(AvailableCores, ThisProcess) {
    cpu_set_t set;
    ASSERT_EQ(sched_getaffinity(0, sizeof set, &set), 0);
    const int affinity = CPU_COUNT(&set);
    const int cores = pf::worker::availableCores();
    EXPECT_GE(cores, 1);
    EXPECT_LE(cores, affinity);
    EXPECT_EQ(cores, coresWithinLimit(affinity, cgroupCpuLimit()));
}
