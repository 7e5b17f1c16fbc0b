"""The convex layer (cvxpy): servo crank-speed profiles and tolerance allocation, on the exact analysis."""
