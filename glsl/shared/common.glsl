// Constants, random numbers and small math helpers shared by every kernel.
#ifndef ILLUM_COMMON_GLSL
#define ILLUM_COMMON_GLSL

const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;
const float INF = 1.0 / 0.0;

// Deterministic per-sample random streams: a stream depends only on (seed, pixel, sample index),
// so any split of a render into sample ranges or tiles reproduces exactly the same samples.
// Two kinds:
// * camera samples (rng_init_camera): draw k takes dimension pair k of a shuffled, Owen-scrambled
//   Sobol (0,2)-sequence over the pixel's sample indices, scrambled per (seed, pixel, k) (Burley
//   2020, "Practical Hash-based Owen Scrambling"; padded pairs, as pbrt-v4's PaddedSobolSampler).
//   Every point is uniform, so every estimator stays unbiased; over a pixel's first 2^m samples
//   (of a split pixel: its first 2^m even, or odd, ones) each pair is stratified in every
//   elementary interval. A single draw takes a pair of its own.
// * everything else (rng_init: cache-update paths, test kernels): PCG, independent draws.
uint hash_u32(uint x) {  // lowbias32 (Wellons)
    x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
    return x;
}
const uint RNG_PCG = 0xffffffffu;  // Rng.dim of a PCG stream
struct Rng { uint state; uint index; uint dim; };
Rng rng_init(uint seed_lo, uint seed_hi, uint pixel, uint sample_index) {
    uint h = hash_u32(seed_lo ^ hash_u32(seed_hi + 0x9e3779b9u));
    h = hash_u32(h ^ pixel);
    h = hash_u32(h ^ (sample_index * 0x85ebca6bu + 0x68e31da4u));
    return Rng(h, 0u, RNG_PCG);
}
Rng rng_init_camera(uint seed_lo, uint seed_hi, uint pixel, uint sample_index, bool split) {
    uint h = hash_u32(seed_lo ^ hash_u32(seed_hi + 0x7f4a7c15u));
    // Split: even and odd samples are two sequences with scrambles of their own, independent, so
    // that the even/odd half-buffers estimate the error (one sequence's halves would be
    // anti-correlated, and the estimate too high). Else one sequence, stratified over all of the
    // pixel's samples: the first sequence of a split pixel.
    uint parity = split ? sample_index & 1u : 0u;
    h = hash_u32(hash_u32(h ^ pixel) ^ parity * 0x2545f491u);
    return Rng(h, split ? sample_index >> 1u : sample_index, 0u);
}
// Laine-Karras hash with Burley 2020's constants: an Owen scramble of x's bits when x holds the
// digits in reverse (least significant bit = first binary digit), each bit changed only by
// itself, lower bits and the seed.
uint lk_scramble(uint x, uint seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}
// Sobol's second dimension with its digits reversed (bit j = digit j + 1): the Pascal matrix
// mod 2, bit j = XOR of the index bits k with k a bit-superset of j (Lucas), as a superset
// transform in five steps; the first dimension reversed is the index itself.
uint sobol1_reversed(uint i) {
    i ^= (i >> 1u) & 0x55555555u;
    i ^= (i >> 2u) & 0x33333333u;
    i ^= (i >> 4u) & 0x0f0f0f0fu;
    i ^= (i >> 8u) & 0x00ff00ffu;
    i ^= (i >> 16u) & 0x0000ffffu;
    return i;
}
// 24 bits to [0, 1), so 1 - u >= 2^-24 (never log(0)).
float rng_float(uint x) { return float(x >> 8) * (1.0 / 16777216.0); }
// Point `index` of dimension pair `dim` of a camera stream.
vec2 rng_sobol2_point(Rng r, uint dim, uint index) {
    uint seed = hash_u32(r.state ^ hash_u32(dim * 0x9e3779b9u + 0x632be5abu));
    // Shuffle: an Owen scramble of the index (Burley 2020), so that pairs are decorrelated. It
    // maps each aligned block of 2^m indices onto an aligned block, so rng_sobol2_group's points
    // stay a (0, m, 2)-net.
    uint i = bitfieldReverse(lk_scramble(bitfieldReverse(index), seed));
    uint x = bitfieldReverse(lk_scramble(i, hash_u32(seed ^ 0xa511e9b3u)));
    uint y = bitfieldReverse(lk_scramble(sobol1_reversed(i), hash_u32(seed ^ 0x63d83595u)));
    return vec2(rng_float(x), rng_float(y));
}
vec2 rng_sobol2(inout Rng r) {
    vec2 p = rng_sobol2_point(r, r.dim, r.index);
    r.dim += 1u;
    return p;
}
// Sample j of the `stride` (a power of two) that one dimension pair gives each camera sample:
// Sobol point index * stride + j. A camera sample's stride points are an aligned block, a
// (0, log2 stride, 2)-net (one point in every elementary interval of area 1 / stride: every row
// and column stratum, every grid cell), and a pixel's first k camera samples take the first
// k * stride points of one (0, 2)-sequence, stratified across samples as well as within them.
// Every point is uniform: estimators stay unbiased.
vec2 rng_sobol2_group(Rng r, uint dim, uint j, uint stride) {
    return rng_sobol2_point(r, dim, r.index * stride + j);
}
// PCG-RXS-M-XS 32.
float rng_pcg(inout Rng r) {
    r.state = r.state * 747796405u + 2891336453u;
    uint w = ((r.state >> ((r.state >> 28u) + 4u)) ^ r.state) * 277803737u;
    return rng_float((w >> 22u) ^ w);
}
float rng_next(inout Rng r) { return r.dim == RNG_PCG ? rng_pcg(r) : rng_sobol2(r).x; }
vec2 rng_next2(inout Rng r) {
    if (r.dim != RNG_PCG) return rng_sobol2(r);
    float a = rng_pcg(r);
    return vec2(a, rng_pcg(r));
}

// floor(x) as an int: exact for |x| <= 2^22, and within [-2^22, 2^22] for every x (NaN and the
// infinities too, so an index made from it stays in range). Lavapipe converts a float to an int
// lane by lane (LLVM 15 does not vectorize its saturating conversion: eight scalar conversions,
// compares and inserts per vector); an add and a bit cast stay in vector registers
// (docs/performance-kernels.md, "Float to int").
int floor_int(float x) {
    return clamp(floatBitsToInt(floor(x) + 12582912.0) - 0x4B400000, -4194304, 4194304);
}
// floor(x) for x >= 0 (NaN reads 2^22), as floor_int.
uint floor_uint(float x) { return uint(max(floor_int(x), 0)); }
// ceil(x) for x >= 0, as floor_int.
uint ceil_uint(float x) { return uint(max(-floor_int(-x), 0)); }
ivec2 floor_int(vec2 v) { return ivec2(floor_int(v.x), floor_int(v.y)); }

// True for NaN and +-Inf; a bit test, since isnan/isinf may be folded away by the compiler.
bool non_finite(float x) { return (floatBitsToUint(x) & 0x7fffffffu) >= 0x7f800000u; }
bool non_finite(vec3 v) { return non_finite(v.x) || non_finite(v.y) || non_finite(v.z); }

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// Orthonormal basis around a unit vector (Duff et al. 2017).
void make_basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// Concentric map of the unit square onto the unit disk (Shirley & Chiu 1997).
vec2 concentric_disk(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
    float r, phi;
    if (abs(o.x) > abs(o.y)) { r = o.x; phi = (PI / 4.0) * (o.y / o.x); }
    else { r = o.y; phi = PI / 2.0 - (PI / 4.0) * (o.x / o.y); }
    return r * vec2(cos(phi), sin(phi));
}

// Inverse trigonometry with float32 accuracy (a few ulp; Cephes atanf's polynomial after reduction
// to |x| <= tan(pi/8)). Vulkan allows atan/asin/acos 4096 ULP and drivers use it: lavapipe's atan
// has 2e-5 relative error and its acos 1.6e-4 absolute (tests/kernels/trig_check.comp), which shows in
// solid angles, texel lookups and the irradiance formulas. sin and cos are accurate in practice.
float atan_unit_interval(float x) {   // x in [0, 1]
    float base = 0.0;
    if (x > 0.41421356) {
        base = 0.25 * PI;
        x = (x - 1.0) / (x + 1.0);
    }
    float z = x * x;
    return base + ((((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z - 3.33329491539e-1) * z * x + x);
}

// atan(y, x) in [-pi, pi]; 0 for (0, 0).
float atan2_accurate(float y, float x) {
    float ax = abs(x), ay = abs(y);
    float hi = max(ax, ay), lo = min(ax, ay);
    if (hi == 0.0) return 0.0;
    float r = atan_unit_interval(lo / hi);
    if (ay > ax) r = 0.5 * PI - r;
    if (x < 0.0) r = PI - r;
    return y < 0.0 ? -r : r;
}

float acos_accurate(float x) {
    x = clamp(x, -1.0, 1.0);
    return atan2_accurate(sqrt(max(0.0, (1.0 - x) * (1.0 + x))), x);
}

float asin_accurate(float x) {
    x = clamp(x, -1.0, 1.0);
    return atan2_accurate(x, sqrt(max(0.0, (1.0 - x) * (1.0 + x))));
}

// Equirectangular (lat-long) map of directions, as the dome and the sphere's surface uv use it:
// the direction is first rotated about +Y by the angle whose (cos, sin) is rot_cos_sin; then
// u = longitude / (2 pi) + 1/2 with longitude atan(r.x, -r.z), v = theta / pi with theta measured
// from +Y (v = 0 at +Y, the top row of the image).
vec2 direction_to_latlong(vec3 d, vec2 rot_cos_sin) {
    vec3 r = vec3(rot_cos_sin.x * d.x - rot_cos_sin.y * d.z, d.y, rot_cos_sin.y * d.x + rot_cos_sin.x * d.z);
    float phi = atan2_accurate(r.x, -r.z);
    float theta = atan2_accurate(length(r.xz), r.y);
    return vec2(phi * (0.5 * INV_PI) + 0.5, theta * INV_PI);
}

// Inverse of direction_to_latlong, given sin and cos of theta = pi uv.y (passed in so that callers
// can compute sin(theta) without cancellation near the poles).
vec3 latlong_to_direction(vec2 uv, float sin_theta, float cos_theta, vec2 rot_cos_sin) {
    float phi = 2.0 * PI * (uv.x - 0.5);
    vec3 r = vec3(sin_theta * sin(phi), cos_theta, -sin_theta * cos(phi));
    // Rotation back: the transpose of the rotation in direction_to_latlong.
    return vec3(rot_cos_sin.x * r.x + rot_cos_sin.y * r.z, r.y, -rot_cos_sin.y * r.x + rot_cos_sin.x * r.z);
}

// Uniform direction on the unit sphere; pdf = 1 / (4 pi).
vec3 uniform_sphere(vec2 u) {
    float z = 1.0 - 2.0 * u.x;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
}

// Cosine-weighted hemisphere about +z; pdf = cos(theta) / pi.
vec3 cosine_hemisphere(vec2 u) {
    vec2 d = concentric_disk(u);
    return vec3(d, sqrt(max(0.0, 1.0 - dot(d, d))));
}

// Ray origin offset off a surface (Waechter & Binder 2019, Ray Tracing Gems ch. 6): integer ULPs
// along the geometric normal, which scales with the magnitude of p; a float offset near the origin.
// Deviation from the paper: every nonzero normal component moves its coordinate by at least 4 ulp.
// Truncating 256 n_i to 0 for |n_i| < 1/256 left the rounding error of a large coordinate (projected
// on n: |n_i| ulp/2) uncovered when the other coordinates are small: a plane with n = (0.003, 0, 1)
// through (6e4, 4e3, 0.085) had correctly rounded hit points whose rays re-hit it
// (tests/stable.rs offset_ray_origin_avoids_self_intersection).
vec3 offset_ray_origin(vec3 p, vec3 ng) {
    const float origin = 1.0 / 32.0;
    const float float_scale = 1.0 / 65536.0;
    const float int_scale = 256.0;
    ivec3 of_i = ivec3(sign(ng) * max(int_scale * abs(ng), 4.0));
    vec3 p_i = vec3(
        intBitsToFloat(floatBitsToInt(p.x) + ((p.x < 0.0) ? -of_i.x : of_i.x)),
        intBitsToFloat(floatBitsToInt(p.y) + ((p.y < 0.0) ? -of_i.y : of_i.y)),
        intBitsToFloat(floatBitsToInt(p.z) + ((p.z < 0.0) ? -of_i.z : of_i.z)));
    return vec3(abs(p.x) < origin ? p.x + float_scale * ng.x : p_i.x,
                abs(p.y) < origin ? p.y + float_scale * ng.y : p_i.y,
                abs(p.z) < origin ? p.z + float_scale * ng.z : p_i.z);
}

#endif
