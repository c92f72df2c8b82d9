"""drd_planner: Bayesian active edge evaluation on expensive graphs.

DiRECt (an offline decision tree over a database of sampled worlds) chooses which graph edge to
collision-check next; BiSECt (an independent-edge Bernoulli model) finishes online. See
``core`` for the ROS-free algorithms, ``data`` for file formats and ``bench`` for the benchmark.
"""

__version__ = "0.1.0"
