// The hybrid's visibility buffer: one r32_uint per pixel, ((instance << PRIM_BITS) | primitive) + 1,
// 0: nothing (the sky). PRIM_BITS (a define) covers the largest mesh's triangle count
// (passes/raytrace_hybrid.py: prim_bits). Attributes are reconstructed by the shading passes.
#ifndef PRIM_BITS
#error "PRIM_BITS must be defined"
#endif

uint vis_encode(uint instance, uint prim) { return ((instance << PRIM_BITS) | prim) + 1u; }
uint vis_instance(uint id) { return (id - 1u) >> PRIM_BITS; }
uint vis_prim(uint id) { return (id - 1u) & ((1u << PRIM_BITS) - 1u); }
