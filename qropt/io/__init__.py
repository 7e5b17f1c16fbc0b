"""What people see and keep: plots, animations, CAD export (DXF, SVG) and the HTML report."""
