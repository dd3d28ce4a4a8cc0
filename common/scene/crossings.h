// Index-matched (null-BSDF) surfaces bend no ray: the path tracer, visibility walks, connections and manifold
// chains pass through them, counting each crossing for Mitsuba's path depth (README "Path depth").
#pragma once

namespace pf {

// Bound on the index-matched surfaces one ray segment crosses, so that coincident null surfaces cannot loop.
inline constexpr int kMaxCrossings = 256;

}  // namespace pf
