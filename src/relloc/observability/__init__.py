"""Observability and accuracy limits of relloc's models.

- :mod:`.lie`: Lie derivatives of a :class:`relloc.models.symbolic.SymbolicModel`'s outputs
  along its vector fields and the observability matrix (pruned, numerically evaluated);
- :mod:`.rank`: row-normalised numeric rank, null space, 50-digit re-check;
- :mod:`.analysis`: generic rank, input conditions, unobservable directions (``analyse``) and
  the rank at given states and constant inputs (``rank_at``);
- :mod:`.builtin`: the models behind ``relloc observability MODEL`` and user entry points;
- :mod:`.rpmg`: seed 001's relative position measurement graph, k-connectivity, β, edge blocks,
  the n-robot observability matrix and its rank formula;
- :mod:`.pcrlb` (public API) / :mod:`.pcrlb_recursion`: the posterior Cramér–Rao lower bound.
"""
