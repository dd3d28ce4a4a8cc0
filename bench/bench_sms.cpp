// Specular manifold sampling against the path tracer, BDPT and MEPT (issue 15's closing figures): equal-time
// relMSE against a long BDPT reference for path, bdpt, mept, sms unbiased and sms biased with M = 1, 4, 8, and unbiased
// sms with two-vertex chains (bounces = 2), on the ring and sphere scenes; the solver's success rate and mean Bernoulli
// trials per solution (the paper's Fig. 6 reports 26-29% and about 6 on its refractive sphere); rays per second of sms
// against path.
//
//     bench_sms [--res N] [--time S] [--ref-spp N] [--threads T] [scene.xml ...]   (default scenes: from the
//     repository root, scenes/ring-caustic and scenes/sphere-caustic)
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bench_support.h"
#include "integrators/path.h"
#include "integrators/sms_connection.h"

namespace {

struct Options {
    int res = 64, refSpp = 512, threads = 0;
    double seconds = 10;
    std::vector<std::string> scenes;
};

pf::Properties integratorProps(const pf::Scene &scene, const std::string &type) {
    pf::Properties props(pf::ObjectKind::Integrator, type, {});
    props.set("maxDepth", pf::Properties::Type::Integer, scene.integratorProperties().getInt("maxDepth", -1), {});
    return props;
}

}  // namespace

int main(int argc, char **argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool more = i + 1 < argc;
        if (a == "--res" && more)
            o.res = std::stoi(argv[++i]);
        else if (a == "--time" && more)
            o.seconds = std::stod(argv[++i]);
        else if (a == "--ref-spp" && more)
            o.refSpp = std::stoi(argv[++i]);
        else if (a == "--threads" && more)
            o.threads = std::stoi(argv[++i]);
        else
            o.scenes.push_back(a);
    }
    if (o.scenes.empty())
        for (const char *name : {"ring-caustic", "sphere-caustic"})
            o.scenes.push_back(std::string("scenes/") + name + "/scene.xml");

    std::printf(
        "equal time %.1f s per render at %dx%d, relMSE (all / without the 0.1%% worst pixels) against "
        "bdpt at %d spp\n",
        o.seconds, o.res, o.res, o.refSpp);
    for (const std::string &path : o.scenes) {
        auto scene = bench::loadWithSampleCount(path, 1, o.res, "bench_sms");
        pf::RenderStats refStats;
        const auto bdpt = pf::createIntegrator("bdpt", integratorProps(*scene, "bdpt"), true);
        const pf::Bitmap reference = bench::renderWith(*scene, *bdpt, o.refSpp, 0, 9999, o.threads, refStats);
        std::printf("\n%s (reference %.1f s)\n", path.c_str(), refStats.seconds);
        std::printf("  %-18s %8s %8s %12s %12s %10s %9s %8s %6s\n", "integrator", "spp", "seconds", "relMSE", "trimmed",
                    "Mrays/s", "success", "trials", "guard");
        const auto row = [&](const std::string &name, const pf::Integrator &integrator, const pf::SmsConnection *sms) {
            pf::RenderStats stats;
            const pf::Bitmap image = bench::renderWith(*scene, integrator, 0, o.seconds, 1, o.threads, stats);
            const bench::RelativeError err = bench::relativeError(image, reference);
            std::printf("  %-18s %8lld %8.2f %12.5g %12.5g %10.2f", name.c_str(),
                        static_cast<long long>(stats.samplesPerPixel), stats.seconds, err.all, err.trimmed,
                        static_cast<double>(stats.rays) / stats.seconds * 1e-6);
            if (sms && !sms->settings().biased)
                std::printf(" %8.1f%% %8.2f %6llu\n", 100 * sms->statistics().successRate(),
                            sms->statistics().meanTrials(),
                            static_cast<unsigned long long>(sms->statistics().guardHits.load()));
            else if (sms)
                std::printf(" %8.1f%%\n", 100 * sms->statistics().successRate());
            else
                std::printf("\n");
        };
        row("path", *pf::createIntegrator("path", integratorProps(*scene, "path"), true), nullptr);
        row("bdpt", *bdpt, nullptr);
        row("mept", *pf::createIntegrator("mept", integratorProps(*scene, "mept"), true), nullptr);
        // (M, bounces): M = 0 is unbiased.
        for (const auto &[m, bounces] : std::vector<std::pair<int, int>>{{0, 1}, {1, 1}, {4, 1}, {8, 1}, {0, 2}}) {
            pf::Properties props = integratorProps(*scene, "sms");
            if (m > 0) {
                props.set("biased", pf::Properties::Type::Boolean, true, {});
                props.set("trials", pf::Properties::Type::Integer, int64_t(m), {});
            }
            if (bounces > 1) props.set("bounces", pf::Properties::Type::Integer, int64_t(bounces), {});
            const auto connection = std::make_shared<pf::SmsConnection>(props);
            const pf::PathTracer sms(props, false, connection);
            row((m == 0 ? "sms unbiased" : "sms biased M=" + std::to_string(m)) +
                    (bounces > 1 ? " bounces=" + std::to_string(bounces) : ""),
                sms, connection.get());
        }
    }
    return 0;
}
