// The cores a worker may use (issue 7: --threads defaults to them): the process's CPU affinity, further
// limited by the CPU bandwidth quota of its control group, which is how container runtimes and
// Kubernetes express a CPU limit (`--cpus 2`, `resources.limits.cpu: 2`). A container sees the host's
// cores in /proc/cpuinfo and usually in its affinity mask, so without the quota a worker would start one
// render thread per host core and be throttled by the kernel's CFS bandwidth controller.
#pragma once
#include <filesystem>
#include <optional>

namespace pf::worker {

// Where the kernel describes this process's control groups; tests point these at fake files whose
// mount points lead into a fake cgroup tree.
struct CgroupSources {
    std::filesystem::path mountinfo = "/proc/self/mountinfo";
    std::filesystem::path cgroup = "/proc/self/cgroup";
};

// The CPU bandwidth limit of this process, in CPUs (quota / period): the tightest over its control group
// and that group's ancestors within the mounted hierarchy (a parent's limit binds its children too, as
// with a Kubernetes pod's cgroup above its containers'). Reads cgroup v2 `cpu.max` and cgroup v1
// `cpu.cfs_quota_us` / `cpu.cfs_period_us`; in hybrid mode both hierarchies are consulted. nullopt when
// no limit is set or nothing can be read.
std::optional<double> cgroupCpuLimit(const CgroupSources &sources = {});

// Render threads for `affinityCores` usable cores under a bandwidth limit of `limit` CPUs: the limit
// rounded up (a fractional limit is used in full; the last thread is throttled part of the time), never
// more than the cores, at least one.
int coresWithinLimit(int affinityCores, std::optional<double> limit);

// The cores this process may use: sched_getaffinity (hardware_concurrency if that fails), limited by
// cgroupCpuLimit().
int availableCores();

}  // namespace pf::worker
