"""The finite-element model: mesh, materials, enrichment, quadrature, the bulk
stiffness, boundary conditions and poroelastic loads.

Modules:

- ``mesh``: structured rectilinear Q4 meshes (uniform or graded);
- ``material``: linear elastic constants;
- ``branch``: near-tip (branch) enrichment functions;
- ``enrichment``: shifted-Heaviside and tip enrichment: enriched nodes and the
  dof map;
- ``quadrature``: sub-cell rules of enriched cells and the interface points on
  fractures;
- ``assembly``: the bulk stiffness, assembled once per run;
- ``boundary``: prescribed displacements, edge tractions, rigid-body pins;
- ``poro``: Biot effective stress in the bulk and Terzaghi pressure on
  fractures.

The subpackage imports nothing itself: import the module you need (``from
xfemslip.fem.mesh import ...``)."""

__all__ = [
    "assembly",
    "boundary",
    "branch",
    "enrichment",
    "material",
    "mesh",
    "poro",
    "quadrature",
]
