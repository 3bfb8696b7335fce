// Probe of a driver's loop limiter (src/render/probe.rs): counts outer x inner iterations of two
// nested loops. Older llvmpipe (Mesa 22.3, Debian 12's stock lavapipe) stops every loop nest after
// 65535 iterations in total without any error, which silently drops samples of long dispatches.
// The loads keep the compiler from folding the count into a closed form.
#version 460
layout(local_size_x = 1) in;
layout(std430, binding = 0) buffer Data { uint ones[2]; uint count; };
layout(push_constant) uniform Push { uint outer; uint inner; };
void main() {
    uint c = 0u;
    for (uint i = 0u; i < outer; ++i)
        for (uint j = 0u; j < inner; ++j) c += ones[j & 1u];
    count = c;
}
