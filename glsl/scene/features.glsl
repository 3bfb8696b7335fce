// The FEATURES specialization constant: what a scene uses (layout.glsl's FEATURE_* bits). Code
// behind has_feature() of an absent bit is folded away at pipeline creation, so LLVM never
// compiles it (docs/performance-kernels.md). Kernels created without it (the sampler and
// irradiance test kernels) keep every feature.
#ifndef ILLUM_FEATURES_GLSL
#define ILLUM_FEATURES_GLSL

#include "shared/layout.glsl"

layout(constant_id = SPEC_FEATURES) const uint FEATURES = 0xffffffffu;
bool has_feature(uint f) { return (FEATURES & f) != 0u; }

// Whether l is of `kind` and the kernel holds that kind's code: its feature bit, the one
// gpu_scene's encode() sets per kind. Called with a literal kind, the bit folds at pipeline
// creation, and so does the code behind an absent kind.
bool light_is(GpuLight l, uint kind) {
    uint f = kind == LIGHT_RECT ? FEATURE_RECT_LIGHTS
           : kind == LIGHT_SPHERE ? FEATURE_SPHERE_LIGHTS
           : kind == LIGHT_DISK ? FEATURE_DISK_LIGHTS
           : kind == LIGHT_SUN ? FEATURE_SUN
           : kind == LIGHT_TRIANGLE ? FEATURE_TRIANGLE_LIGHTS
           : FEATURE_DOME;
    return has_feature(f) && l.kind == kind;
}

#endif
