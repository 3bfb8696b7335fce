// The FEATURES specialization constant: what a scene uses (layout.glsl's FEATURE_* bits). Code
// behind has_feature() of an absent bit is folded away at pipeline creation, so LLVM never
// compiles it (docs/performance-kernels.md). Kernels created without it (the sampler and
// irradiance test kernels) keep every feature.
#ifndef ILLUM_FEATURES_GLSL
#define ILLUM_FEATURES_GLSL

#include "layout.glsl"

layout(constant_id = SPEC_FEATURES) const uint FEATURES = 0xffffffffu;
bool has_feature(uint f) { return (FEATURES & f) != 0u; }

#endif
