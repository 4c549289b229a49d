"""The shared geometry layer: one operation per module, plain ``(V, F)`` arrays in and out.

Every pipeline (placement, rig_transfer, landmarks, expressions) imports from here; nothing
here imports a pipeline. ``V`` is ``(n, 3)`` float64 in the caller's frame and units, ``F``
``(m, 3)`` int64 triangles.
"""
