#!/usr/bin/env python3
"""Write the two Newton comparison problems (issue 14) for Fetouch and CalculiX.

Cook's membrane (a tapered panel clamped on its left edge, sheared on its right edge, one element
thick with both faces on rollers: plane strain) and a block pressed on its top, both hexahedral,
nearly incompressible neo-Hookean, four equal load steps. For each problem this writes, into the
output folder:

  NAME.vtu   the mesh for Fetouch (hexahedra, metres)
  NAME.yaml  a Fetouch scene using that mesh (`fetouch solve NAME.yaml --steps 4 --json`)
  NAME.inp   the same mesh, supports, load and steps for CalculiX (`ccx -i NAME`)

Usage: make_problems.py OUT_DIR [--cells N]
"""
import argparse
import os

NU = 0.45


def cook(n):
    """Nodes (x, y, z) and hexahedra of Cook's membrane, n x n x 1 cells; thickness 4 mm."""
    t = 0.004
    corners = [(0.0, 0.0), (0.048, 0.044), (0.048, 0.060), (0.0, 0.044)]
    nodes = []
    for k in range(2):
        for j in range(n + 1):
            for i in range(n + 1):
                s, r = i / n, j / n
                x = sum(w * c[0] for w, c in zip(bilinear(s, r), corners))
                y = sum(w * c[1] for w, c in zip(bilinear(s, r), corners))
                nodes.append((x, y, k * t))
    return nodes, structured_cells(n, n, 1), t


def block(n):
    """A 10 x 10 x 5 cm block, n x n x n/2 cells."""
    nz = max(1, n // 2)
    nodes = [(0.1 * i / n, 0.1 * j / n, 0.05 * k / nz)
             for k in range(nz + 1) for j in range(n + 1) for i in range(n + 1)]
    return nodes, structured_cells(n, n, nz)


def bilinear(s, r):
    return [(1 - s) * (1 - r), s * (1 - r), s * r, (1 - s) * r]


def structured_cells(nx, ny, nz):
    def node(i, j, k):
        return (k * (ny + 1) + j) * (nx + 1) + i
    cells = []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                cells.append([node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k),
                              node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1),
                              node(i, j + 1, k + 1)])
    return cells


def faces_on(nodes, cells, test):
    """Cell faces (4 node ids, any order) whose four nodes all pass test(x, y, z)."""
    local = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    out = []
    for c in cells:
        for f in local:
            ids = [c[v] for v in f]
            if all(test(*nodes[v]) for v in ids):
                out.append(ids)
    return out


def consistent_loads(nodes, faces, traction):
    """Nodal forces of a uniform dead traction on bilinear quadrilaterals (area / 4 per corner,
    exact for parallelograms)."""
    loads = {}
    for f in faces:
        a, b, c, d = (nodes[v] for v in f)
        u = [c[i] - a[i] for i in range(3)]
        v = [d[i] - b[i] for i in range(3)]
        cross = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        area = 0.5 * sum(x * x for x in cross) ** 0.5
        for node in f:
            acc = loads.setdefault(node, [0.0, 0.0, 0.0])
            for i in range(3):
                acc[i] += traction[i] * area / 4
    return loads


def write_vtu(path, nodes, cells):
    with open(path, "w") as out:
        out.write('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1">\n<UnstructuredGrid>\n')
        out.write(f'<Piece NumberOfPoints="{len(nodes)}" NumberOfCells="{len(cells)}">\n')
        out.write('<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">\n')
        out.write("\n".join(f"{x:.17g} {y:.17g} {z:.17g}" for x, y, z in nodes))
        out.write('\n</DataArray></Points>\n<Cells>\n<DataArray type="Int64" Name="connectivity" format="ascii">\n')
        out.write("\n".join(" ".join(str(v) for v in c) for c in cells))
        out.write('\n</DataArray>\n<DataArray type="Int64" Name="offsets" format="ascii">\n')
        out.write(" ".join(str(8 * (i + 1)) for i in range(len(cells))))
        out.write('\n</DataArray>\n<DataArray type="UInt8" Name="types" format="ascii">\n')
        out.write(" ".join("12" for _ in cells))
        out.write("\n</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")


SCENE = """# {title} (written by scripts/calculix/make_problems.py; the CalculiX twin is {name}.inp)
name: {name}
units: SI
mesh: {{file: {name}.vtu, element: q1}}
material: {{model: neo_hookean_incompressible, youngs_modulus_pa: {e}, poisson_ratio: {nu}}}
boundary:
{boundary}
solver:
  newton: {{relative_tolerance: 1.0e-8, max_iterations: 50, line_search: true}}
  linear_solver: direct
probes:
  - {{name: tool, radius_m: 0.005, device: {{type: replay, trajectory: unused.csv}}}}
"""


def plane(axis, at):
    normal = {"x": "[1, 0, 0]", "y": "[0, 1, 0]", "z": "[0, 0, 1]"}[axis]
    point = {"x": f"[{at}, 0, 0]", "y": f"[0, {at}, 0]", "z": f"[0, 0, {at}]"}[axis]
    return f"{{plane: {{point: {point}, normal: {normal}}}}}"


def write_inp(path, title, modulus, nodes, cells, supports, loads):
    with open(path, "w") as out:
        out.write(f"** {title} (scripts/calculix/make_problems.py)\n*NODE, NSET=NALL\n")
        for i, (x, y, z) in enumerate(nodes):
            out.write(f"{i + 1}, {x:.12g}, {y:.12g}, {z:.12g}\n")
        out.write("*ELEMENT, TYPE=C3D8, ELSET=EALL\n")
        for i, c in enumerate(cells):
            out.write(f"{i + 1}, " + ", ".join(str(v + 1) for v in c) + "\n")
        out.write("*BOUNDARY\n")
        for node, dofs in sorted(supports.items()):
            for d in sorted(dofs):
                out.write(f"{node + 1}, {d}, {d}, 0.\n")
        # W = C10 (I1bar - 3) + (J - 1)^2 / D1: C10 = mu / 2, D1 = 2 / kappa (the same small-strain
        # moduli as Fetouch's kappa/4 (J^2 - 1 - 2 ln J); the two volumetric laws differ at O((J-1)^3)).
        out.write("*MATERIAL, NAME=TISSUE\n*HYPERELASTIC, NEO HOOKE\n")
        mu, kappa = modulus / (2 * (1 + NU)), modulus / (3 * (1 - 2 * NU))
        out.write(f"{mu / 2:.10e}, {2 / kappa:.10e}\n*SOLID SECTION, ELSET=EALL, MATERIAL=TISSUE\n")
        # Newton to a relative residual of 1e-8 (R_alpha_n, R_alpha_p), never cutting a step on slow
        # convergence (I_0 .. I_A large).
        out.write("*STEP, NLGEOM, INC=1000\n*STATIC, DIRECT\n0.25, 1.0\n")
        out.write("*CONTROLS, PARAMETERS=TIME INCREMENTATION\n40, 50, 50, 50, 50, 50, 50, 50\n")
        out.write("*CONTROLS, PARAMETERS=FIELD, FIELD=DISPLACEMENT\n1e-8, 1e-8, , , 0.02, 1e-5, 1e-3, 1e-8\n")
        out.write("*CLOAD\n")
        for node, f in sorted(loads.items()):
            for d in range(3):
                if f[d] != 0.0:
                    out.write(f"{node + 1}, {d + 1}, {f[d]:.12g}\n")
        out.write("*NODE PRINT, NSET=NALL\nU\n*END STEP\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("--cells", type=int, default=16)
    # Both codes see the same strains whatever the modulus, but CalculiX has absolute thresholds
    # (tuned for N and mm) that a soft tissue's millinewtons in SI units pass at once: a stiff
    # modulus keeps its convergence test relative, as Fetouch's is.
    parser.add_argument("--modulus", type=float, default=5.0e6, help="Young's modulus, Pa")
    parser.add_argument("--shear", type=float, default=0.04, help="Cook's shear traction / E")
    parser.add_argument("--press", type=float, default=0.12, help="the block's top pressure / E")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    n = args.cells
    eps = 1e-9

    # Cook's membrane: shear on the right edge (0.04 E: tip deflection about a quarter of the span).
    nodes, cells, t = cook(n)
    shear = [0.0, args.shear * args.modulus, 0.0]
    loads = consistent_loads(nodes, faces_on(nodes, cells, lambda x, y, z: abs(x - 0.048) < eps), shear)
    supports = {}
    for i, (x, y, z) in enumerate(nodes):
        if abs(x) < eps:
            supports.setdefault(i, set()).update({1, 2, 3})
        if abs(z) < eps or abs(z - t) < eps:
            supports.setdefault(i, set()).add(3)
    write_problem(args.out, args.modulus, "cook", "Cook's membrane, plane strain, sheared", nodes, cells, supports, loads,
                  [("clamp", "fixed", plane("x", 0), ""),
                   ("front", "roller", plane("z", 0), ""),
                   ("back", "roller", plane("z", t), ""),
                   ("shear", "traction", plane("x", 0.048), f"traction_pa: {shear}")])

    # The block: fixed base, pressed down on the whole top (0.12 E: about 15 % compression).
    nodes, cells = block(n)
    press = [0.0, 0.0, -args.press * args.modulus]
    loads = consistent_loads(nodes, faces_on(nodes, cells, lambda x, y, z: abs(z - 0.05) < eps), press)
    supports = {i: {1, 2, 3} for i, (x, y, z) in enumerate(nodes) if abs(z) < eps}
    write_problem(args.out, args.modulus, "block", "A block pressed on its top", nodes, cells, supports, loads,
                  [("base", "fixed", plane("z", 0), ""),
                   ("top", "traction", plane("z", 0.05), f"traction_pa: {press}")])


def write_problem(out, modulus, name, title, nodes, cells, supports, loads, regions):
    write_vtu(os.path.join(out, name + ".vtu"), nodes, cells)
    boundary = "\n".join(
        f"  - {{name: {r}, type: {kind}, select: {sel}{', ' + extra if extra else ''}}}"
        for r, kind, sel, extra in regions)
    with open(os.path.join(out, name + ".yaml"), "w") as f:
        f.write(SCENE.format(title=title, name=name, e=modulus, nu=NU, boundary=boundary))
    write_inp(os.path.join(out, name + ".inp"), title, modulus, nodes, cells, supports, loads)


if __name__ == "__main__":
    main()
