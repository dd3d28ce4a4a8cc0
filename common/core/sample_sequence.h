// Which numbers the pixel samples of image tasks draw, as the scene's <sampler> asks: the sensor keeps this
// small description, and only the code that draws the numbers (render/image_task.cpp, through
// makePixelSampler) includes the samplers themselves (core/ld_sampler.h, core/global_sobol_sampler.h).
#pragma once

namespace pf {

struct SampleSequence {
    bool lowDiscrepancy = false;
    // The 1D requests and, separately, the 2D requests of a sample that get stratified numbers (Mitsuba's
    // `dimension`); 0: all of them.
    int dimension = 0;
    // One Sobol sequence through the whole image (core/global_sobol_sampler.h; `sobol` with layout "image")
    // instead of each pixel's own padded one.
    bool acrossPixels = false;
};

}  // namespace pf
