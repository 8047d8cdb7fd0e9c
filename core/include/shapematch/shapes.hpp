#pragma once
// Meshes built in code: for tests and for the bundled assets (the project makes its own).
#include "shapematch/mesh.hpp"

namespace shapematch::shapes {

Mesh tetrahedron();
Mesh octahedron();
// Icosahedron subdivided `subdivisions` times (20 * 4^s faces), projected to the sphere.
Mesh icosphere(int subdivisions, double radius = 1.0);
// A closed genus-1 torus (for genus tests): `n_major` x `n_minor` quads split into triangles.
Mesh torus(int n_major, int n_minor, double major_radius = 1.0, double minor_radius = 0.3);

// The bundled demo object: an asymmetric capsule-shaped "finger" with a knuckle bump, bent by
// `bend_degrees` around its middle joint, with the same connectivity for every bend angle, so
// vertex i of one pose corresponds to vertex i of another (identity ground truth).
// `rings` x `segments` controls the resolution (about 2*rings*segments faces).
// Large bends (beyond about 100 degrees) make the inside of the joint intersect itself.
Mesh bent_finger(double bend_degrees, int rings = 24, int segments = 16);

// The bundled demo pair: a dolphin-like tube, thick behind the head and thin at a tail
// flattened into horizontal flukes, with a dorsal fin on +y, its spine turned up or down by the
// given angles at a head joint and a tail joint, then laid along (1, 0, -1). Only the
// orientation-reversing mirror is a symmetry. Same connectivity for all angles (identity ground
// truth); 2*rings*segments faces.
Mesh dolphin(double head_bend_degrees, double tail_bend_degrees, int rings = 30, int segments = 20);

// Writes the bundled assets into `dir` (created if missing): dolphin_straight.off and
// dolphin_swimming.off (the demo pair), finger_straight.off (10 degrees) and finger_bent.off
// (70 degrees); 1200 faces each, each pair sharing connectivity.
void write_bundled_assets(const std::string& dir);

}  // namespace shapematch::shapes
