// The embedded render loop shared by every SamplingIntegrator: a sequence of ImageTasks (the same
// tasks the farm distributes), merged in order, under a sample count or a wall-time budget.
#include <chrono>
#include <cstdio>
#include <thread>

#include "image/film.h"
#include "integrators/integrator.h"
#include "integrators/progress_bar.h"
#include "render/image_task.h"
#include "scene/scene.h"

namespace pf {

Spectrum SamplingIntegrator::sample(const Scene &scene, Sampler &sampler, const Vec2 &raster, SplatList &) const {
    const Sensor &sensor = scene.sensor();
    const Vec2 aperture = sensor.deltaAperture() ? Vec2(0.5, 0.5) : sampler.next2D();
    Ray ray;
    const Spectrum weight = sensor.sampleRay(ray, raster, aperture);
    return weight.isBlack() ? Spectrum() : weight * Li(scene, sampler, ray);
}

Bitmap SamplingIntegrator::render(const Scene &scene, const RenderOptions &opt, RenderStats &stats) const {
    using Clock = std::chrono::steady_clock;
    const Film &film = scene.sensor().film();
    const int threads =
        opt.threads > 0 ? opt.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const bool timed = opt.timeLimit > 0;
    const int64_t targetSpp = timed ? 0 : (opt.spp > 0 ? opt.spp : scene.sensor().sampleCount());

    ImageBlock image = makeFilmBlock(scene);
    ProgressBar progress(opt.progress);
    const auto start = Clock::now();
    int64_t done = 0;
    ImageTask last{0, 0};
    double lastTaskSeconds = 0;
    for (;;) {
        const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
        // A time budget's passes are sized by the clock (whole passes only), a sample budget's by the fixed
        // sequence the farm shares.
        const int64_t size = timed ? timedPassSize(opt.timeLimit, elapsed, last, lastTaskSeconds)
                                   : imageTaskSize(targetSpp, done, filmPixels(film));
        if (size <= 0) break;
        const ImageTask task{done, size};
        const ImageTaskResult r = runImageTask(scene, *this, opt.seed, task, threads);
        image.merge(r.block);
        done += task.sampleCount;
        stats.rays += r.rays;
        last = task;
        lastTaskSeconds = r.seconds;

        const double total = std::chrono::duration<double>(Clock::now() - start).count();
        char label[64];
        std::snprintf(label, sizeof label, "%lld spp, %.1f s", static_cast<long long>(done), total);
        progress.update(timed ? total / opt.timeLimit : static_cast<double>(done) / targetSpp, label);
        if (opt.onPass) opt.onPass(done, film.develop(image, 1.0 / static_cast<double>(done)));
    }
    stats.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    stats.samplesPerPixel = done;
    stats.samples = static_cast<uint64_t>(done) * film.cropWidth() * film.cropHeight();
    return film.develop(image, done > 0 ? 1.0 / static_cast<double>(done) : 0.0);
}

}  // namespace pf
