// Where a kernel's time goes, by region of its source (measurement only; docs/
// performance-kernels.md, "Kernel regions"). Built in when `cargo build` runs with
// ILLUM_PROFILE_KERNELS=1 (build.rs defines ILLUM_PROFILE); otherwise every macro is empty.
//
// PROF(r) adds the device clock's time since the previous mark to region r, and counts the mark:
// a mark ends the region the code before it belongs to. What a mark costs itself (a clock read)
// is measured on empty spans at the start (PROF_EMPTY) and taken off each region per mark. The
// clock is read once per SIMD group on lavapipe, so a region is charged what the group spent in
// it, divergent lanes included; every invocation adds the same figure, and the host compares
// shares, not absolute times. Only primary.comp and path.comp report (PROF_START .. PROF_END);
// the marks direct_lighting() makes inside full.comp are read and dropped.
#ifndef ILLUM_PROFILE_GLSL
#define ILLUM_PROFILE_GLSL

#include "shared/layout.glsl"

// The regions (PROF_*) are numbered in shared/layout.glsl, where the host reads them too.

#ifdef ILLUM_PROFILE
#extension GL_EXT_shader_realtime_clock : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_buffer_reference : require

layout(buffer_reference, std430, buffer_reference_align = 8) buffer ProfileRef { uint64_t v[]; };

uint64_t prof_time[PROFILE_REGIONS];
uint prof_count[PROFILE_REGIONS];
uint64_t prof_last;

void prof_mark(int r) {
    uint64_t t = clockRealtimeEXT();
    // The compiler may move a clock read past its neighbour's: no negative spans.
    prof_time[r] += t > prof_last ? t - prof_last : 0ul;
    prof_count[r] += 1u;
    prof_last = max(t, prof_last);
}
void prof_start() {
    for (int i = 0; i < PROFILE_REGIONS; ++i) {
        prof_time[i] = 0ul;
        prof_count[i] = 0u;
    }
    prof_last = clockRealtimeEXT();
    for (int i = 0; i < 4; ++i) prof_mark(PROF_EMPTY);
}
// Adds this invocation's times, then its mark counts, to slot `slot` of the profile buffer
// (address 0: none).
void prof_end(uint64_t address, uint slot) {
    prof_mark(PROF_OTHER);
    if (address == 0ul) return;
    ProfileRef p = ProfileRef(address);
    uint base = slot * uint(2 * PROFILE_REGIONS);
    for (int i = 0; i < PROFILE_REGIONS; ++i) {
        p.v[base + uint(i)] += prof_time[i];
        p.v[base + uint(PROFILE_REGIONS + i)] += uint64_t(prof_count[i]);
    }
}
#define PROF_START() prof_start()
#define PROF(r) prof_mark(r)
#define PROF_END(address, slot) prof_end(address, slot)
#else
#define PROF_START()
#define PROF(r)
#define PROF_END(address, slot)
#endif

#endif
