# shellcheck shell=bash
# The benchmark scenes at their reference cameras (../shared/meshes/README.md), as `aperture
# bench` flags, and procedural scenes of 100k to 40M triangles: sourced by the bench scripts
# that compare the frame loop with bare Embree, from the project root.
M=../shared/meshes
declare -A SCENES=(
  [bunny]="--mesh $M/stanford/bun_zipper.ply --eye -0.02,0.11,0.35 --at -0.017,0.11,0 --up 0,1,0 --fov 30"
  [dragon]="--mesh $M/stanford/dragon_vrip.ply --eye 0,0.12,0.45 --at 0,0.12,0 --up 0,1,0 --fov 30"
  [crown]="--mesh $M/scenes/crown_flat.ply --eye 0,5.5,24 --at 0,11,-10 --up 0,1,0 --fov 47 --fov-axis x"
  [bathroom]="--mesh $M/scenes/contemporary-bathroom_flat.ply --eye 0.00724,0.91240,-0.22758 --dir -0.751879,0.015471,-0.659119 --up 0.0116337,0.99988,0.0101985 --fov 55"
  [procedural100k]="--mesh procedural:spheres?tris=100000"
  [procedural1M]="--mesh procedural:spheres?tris=1000000"
  [procedural10M]="--mesh procedural:spheres?tris=10000000"
  [procedural40M]="--mesh procedural:spheres?tris=40000000"
)
