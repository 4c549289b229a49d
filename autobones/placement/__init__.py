"""``autobones place``: bones and smooth skin weights on a head with no landmarks.

The bone-placement method of ``place`` (average-linkage grouping by depth, k-means facial bones
at a chosen density, smooth skinning), one module a stage:

- ``segment``: average-linkage clustering of the head by depth into face, middle and back; the
  head and neck bones;
- ``facial_bones``: mirror-symmetric k-means facial bones on the facial mask;
- ``skin_weights``: bone heat (heat diffusion from each bone) on the intrinsic Laplacian;
- ``locality``: the heat weights kept local (facial bones on the face, a still neck base, a
  neck-free skull);
- ``pipeline``: :func:`place`, which runs load -> orient -> segment -> facial bones -> weights -> locality and
  returns a :class:`autobones.rig.Rig`.
"""
from .pipeline import place

__all__ = ["place"]
