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
    const int64_t pixels = filmPixels(film);
    int64_t done = 0;
    uint64_t samples = 0;  // pixel samples taken, which is also the light paths BDPT traced
    ImageTask last{0, 0};
    double lastTaskSeconds = 0;
    std::vector<float> lastTileSeconds;
    for (bool partial = false; !partial;) {
        const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
        // A time budget's passes are sized by the clock, a sample budget's by the fixed sequence the farm
        // shares. When not even one sample per pixel fits in the time left, a last pass takes one sample in
        // as many of the film's tiles as fit.
        ImageTask task{done, timed ? timedPassSize(opt.timeLimit, elapsed, last, lastTaskSeconds)
                                   : imageTaskSize(targetSpp, done, pixels)};
        if (task.sampleCount <= 0 && timed) {
            task = ImageTask{
                done, 1,
                timedPartialTiles(opt.timeLimit, elapsed, last, lastTaskSeconds, filmTiles(film), lastTileSeconds)};
            partial = true;
        }
        if (task.sampleCount <= 0 || task.tiles == 0) break;
        ImageTaskResult r = runImageTask(scene, *this, opt.seed, task, threads);
        if (partial)
            mergeCoveredPixels(image, std::move(r.block), film, task.tiles);
        else
            image.merge(r.block);
        samples += r.samples;
        if (partial)
            stats.partialPassPixels = static_cast<int64_t>(r.pixels);
        else
            done += task.sampleCount;
        stats.rays += r.rays;
        last = task;
        lastTaskSeconds = r.seconds;
        lastTileSeconds = std::move(r.tileSeconds);

        const double total = std::chrono::duration<double>(Clock::now() - start).count();
        char label[64];
        std::snprintf(label, sizeof label, "%.4g spp, %.1f s", static_cast<double>(samples) / pixels, total);
        progress.update(timed ? total / opt.timeLimit : static_cast<double>(done) / targetSpp, label);
        if (opt.onPass) opt.onPass(done, film.develop(image, splatScale(pixels, done, stats.partialPassPixels)));
    }
    stats.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    stats.samplesPerPixel = done;
    stats.samples = samples;
    return film.develop(image, splatScale(pixels, done, stats.partialPassPixels));
}

}  // namespace pf
