// Internal switches between a physics kernel's vector path and its one-by-one path, for the
// tests that compare the two (both give identical bits). Process-wide; each returns whether its
// vector path is now in use (never where the CPU lacks the instructions).
#pragma once

namespace dynahand::physics {

// World::step prepares the surface rows eight at a time (the SIMD layer, default on) or one
// at a time.
bool useWideSurfacePrepare(bool enabled);
// World::step solves the surface rows a batch of eight at a time (the SIMD layer above its
// scalar level, default on) or row by row.
bool useVectorSweeps(bool enabled);

}  // namespace dynahand::physics
