"""Kinematics: the math namespaces (numpy, Taylor jets, CasADi), the closures every loop is written with, the
exact cycle search and the compiled kernels. Nothing here knows about synthesis."""
