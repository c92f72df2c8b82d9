"""An imitation-learned LazySP selector (StrOLL idea; Bhardwaj, Choudhury, Boots, Srinivasa, RSS 2019).

"Leveraging Experience in Lazy Search" casts LazySP's edge selection as an MDP and imitates an oracle
that knows the world. Reimplemented from that idea (registry name ``lazysp_imitation``) on the loop of
:class:`drd_planner.core.lazysp.LazySP`.

The MDP: state s = LazySP's state (the outcomes so far, so the known-blocked set K, and the lazy shortest
path without K); action = an unchecked edge of that path; cost 1 per check; ends when it is checked free.

The oracle (:class:`ClairvoyantOracle`, a training world whose outcomes are all known). R(s) = checks
of a greedy clairvoyant *rollout*: while the lazy path has blocked edges, check the blocked one whose
deletion lengthens the lazy shortest path most (a bridge first, ties to the earlier edge); then check
the path's remaining unchecked (free) edges. Its blocked checks S(K) and final path P(K) depend on K
only, so rollouts are memoised on K. Q*(s, e) = 1 + cost-to-go after e's true outcome:

- e free: the lazy graph and every later path are unchanged, so no new rollout:
  Q* = 1 + R(s) - [e on P(K)].
- e blocked: the better of two clairvoyant continuations, e's own rollout and following S(K) (which
  still ends on P(K): every path shorter than P(K) in the graph without K + e keeps an edge of S(K)):
  Q* = 1 + min(R(K + e), R(s) - [e in S(K)]).

Q* is an approximation, an upper bound, of the optimal cost-to-go: the greedy order of blocked checks
is not optimal (finding the fewest blocked checks is a hard search problem) and shortest-path ties are
ignored. The clairvoyant is indifferent between a blocked check of S(K) and a free check of P(K); a
learner that cannot see P(K) is not, so the regret target adds ``free_penalty`` (1 check by default)
to free candidates: fail fast among the oracle's equally good checks (measured: it helps on 2D sets).

Features (:func:`candidate_features`) per unchecked path edge, from the training-world posterior of
:class:`~drd_planner.bench.lazysp_learned.PosteriorLazySP` (kappa = ``DEFAULT_PSEUDO_COUNT`` = 20):
P(blocked | outcomes), the marginal P(blocked), Delta-len / path length (capped at :data:`DELTA_CAP`;
bridges at the cap, plus a bridge indicator), their product, the position along the path, edge length /
path length, a first-unchecked indicator and a bias. In training the posterior leaves out the episode's world.

The learner: ridge regression (numpy, closed form: deterministic and cheap next to the oracle) of the
regret Q* - min_state Q*, each visited state weighing 1 in all (1/k per candidate). Only the order within
a state matters; the regret removes the state's level (its distance to the end, which no per-edge feature
predicts) and the weights keep long-path states from dominating. The policy checks the argmin of the
predicted regret; ties go to the higher posterior, then the earlier edge.

Training (:func:`train_imitation_selector`): DAgger. Round 0 rolls in with the oracle, rounds 1..r with
the learned policy (the oracle with probability ``beta`` per step), aggregating (features, Q*) at every
visited state and refitting each round. Worlds: a seeded permutation of the training worlds,
``worlds_per_round`` new ones per round; each episode is capped at ``max_steps`` states and each round
at its share of a Dijkstra work budget (vertex visits: deterministic, unlike a time limit). All
randomness comes from ``seed``: the same inputs give the same weights.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Final

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.bench.lazysp_learned import PosteriorLazySP, PosteriorSettings, all_edge_outcomes
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.posterior import TrainingOutcomes
from drd_planner.core.problem import Problem
from drd_planner.exceptions import ProblemError

#: Registry name of the learned selector.
IMITATION_POLICY: Final = "lazysp_imitation"
#: Delta-len / path length is capped here; a bridge (infinite Delta-len) gets the cap.
DELTA_CAP: Final = 4.0
#: The feature columns of :func:`candidate_features`, in order.
_NAMES = "bias posterior marginal delta bridge posterior_x_delta position length first_open"
FEATURE_NAMES: Final = tuple(_NAMES.split())
#: kappa of the posterior features (``drd_planner.core.policies.DEFAULT_PSEUDO_COUNT``).
PSEUDO_COUNT: Final = 20.0
#: Fixed cost of one Dijkstra call in the work count, in vertex visits (the call's overhead).
CALL_WORK: Final = 500


@dataclass(frozen=True, eq=False)
class ImitationModel:
    """A trained linear selector: predicted regret = ``features @ weights``.

    Attributes:
        weights: (F,) float64, one per :data:`FEATURE_NAMES` entry, in checks per unit feature.
        feature_names: the F feature names.
        stats: training statistics (rounds, episodes, states, samples, seconds, ...).
    """

    weights: FloatArray
    feature_names: tuple[str, ...] = FEATURE_NAMES
    stats: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        w = np.asarray(self.weights, dtype=np.float64)
        if w.shape != (len(self.feature_names),) or not np.all(np.isfinite(w)):
            raise ProblemError(f"imitation weights must be ({len(FEATURE_NAMES)},) finite; got {w.shape}")
        object.__setattr__(self, "weights", w)


def candidate_features(
    posterior: FloatArray,
    marginal: FloatArray,
    delta: FloatArray,
    lengths: FloatArray,
    positions: IntArray,
    path_lengths: FloatArray,
) -> FloatArray:
    """(k, F) float64 features of the k unchecked edges of one path (columns :data:`FEATURE_NAMES`).

    Args:
        posterior: (k,) P(blocked | outcomes so far).
        marginal: (k,) training marginal P(blocked).
        delta: (k,) growth of the lazy shortest path length when the edge is deleted (inf: bridge),
            in length units.
        lengths: (k,) edge lengths, in length units.
        positions: (k,) int positions of the edges on the path (0 = first edge), increasing.
        path_lengths: (n,) lengths of all n edges of the path, in length units.
    """
    k, n = posterior.size, path_lengths.size
    total = max(float(path_lengths.sum()), 1e-12)
    bridge = np.isinf(delta)
    rel = np.where(bridge, DELTA_CAP, np.minimum(np.where(bridge, 0.0, delta) / total, DELTA_CAP))
    columns = (np.ones(k), posterior, marginal, rel, bridge, posterior * rel, positions / max(n - 1, 1))
    return np.stack([*columns, lengths / total, np.arange(k) == 0], axis=1).astype(np.float64)


class ImitationLazySP(PosteriorLazySP):
    """LazySP whose selector checks the path edge with the least predicted regret.

    Args:
        graph: the explicit graph.
        start: start vertex.
        goal: goal vertex.
        outcomes: the training worlds over all E edges (:func:`~drd_planner.bench.lazysp_learned.all_edge_outcomes`).
        model: the trained selector (None: features only, for training; ``select`` then raises).
        name: registry name.
    """

    def __init__(
        self,
        graph: ExplicitGraph,
        start: int,
        goal: int,
        outcomes: TrainingOutcomes,
        model: ImitationModel | None,
        *,
        name: str = IMITATION_POLICY,
    ) -> None:
        self._model = model
        self._marginal = 1.0 - np.asarray(outcomes.marginal, dtype=np.float64)
        settings = PosteriorSettings(pseudo_count=PSEUDO_COUNT, delta=True)
        super().__init__(graph, start, goal, outcomes, settings, name=name)

    def open_features(self) -> tuple[IntArray, FloatArray] | None:
        """(positions (k,) of the unchecked path edges, their (k, F) features); None when none is left."""
        path = self.proposed_path()
        if path is None:
            return None
        open_pos = np.flatnonzero(self._outcome[path] < 0)
        if open_pos.size == 0:
            return None
        edges, lengths = path[open_pos], self._lengths
        posterior, delta = self.blocked_probability()[edges], self.delta_lengths(edges)
        feats = candidate_features(posterior, self._marginal[edges], delta, lengths[edges], open_pos, lengths[path])
        return open_pos, feats

    def _position(self, path: IntArray, checked: BoolArray) -> int:
        if self._model is None:
            raise ProblemError("ImitationLazySP needs a trained model to select (train_imitation_selector)")
        found = self.open_features()
        assert found is not None  # select() calls this only with an unchecked edge on the path
        open_pos, feats = found
        return int(open_pos[ranked_choice(feats @ self._model.weights, feats[:, 1])])


def ranked_choice(score: FloatArray, posterior: FloatArray) -> int:
    """Index of the least ``score`` (k,); ties (relative 1e-9) to the higher posterior, then the first."""
    best = float(score.min())
    tied = np.flatnonzero(score <= best + 1e-9 * max(abs(best), 1.0))
    return int(tied[int(np.argmax(posterior[tied]))])


class ClairvoyantOracle:
    """Q* of the module docstring for one fully known world.

    Args:
        graph, start, goal: the explicit graph and the query's start and goal vertices.
        world_free: (E,) bool, True where the edge is free in this world.

    Attributes:
        work: Dijkstra work so far, in vertex visits (graph copies x vertices + :data:`CALL_WORK` per call).
    """

    def __init__(self, graph: ExplicitGraph, start: int, goal: int, world_free: npt.ArrayLike) -> None:
        free = np.asarray(world_free, dtype=bool)
        if free.shape != (graph.num_edges,):
            raise ProblemError(f"world_free must be ({graph.num_edges},) bool; got shape {free.shape}")
        self._arcs = GraphArcs(graph)
        self._lengths = np.asarray(graph.lengths, dtype=np.float64)
        self._start, self._goal, self.world_free = int(start), int(goal), free
        self._memo: dict[frozenset[int], tuple[tuple[int, ...], IntArray | None]] = {}
        self.work = 0
        self.num_vertices = graph.num_vertices

    def _paths_without(self, weights: FloatArray, edges: list[int]) -> list[IntArray | None]:
        """Shortest path (edge ids; None: cut off) with each of ``edges`` (-1: none) deleted: one Dijkstra."""
        self.work += len(edges) * self._arcs.num_vertices + CALL_WORK
        ids = np.asarray(edges, dtype=np.int64)
        return self._arcs.deletion_paths(self._start, self._goal, weights, ids)

    def blocked_phase(self, blocked: frozenset[int]) -> tuple[tuple[int, ...], IntArray | None]:
        """The greedy rollout from known-blocked set ``blocked``: (its blocked checks in order, final path).

        The final path is None when the rollout cuts start and goal apart.
        """
        if blocked in self._memo:
            return self._memo[blocked]
        weights = self._lengths.copy()
        weights[list(blocked)] = np.inf
        known = set(blocked)
        chain: list[tuple[frozenset[int], int]] = []
        path = self._paths_without(weights, [-1])[0]
        while True:
            key = frozenset(known)
            if key in self._memo:
                picks, final = self._memo[key]
                break
            bad = [] if path is None else path[~self.world_free[path]].tolist()
            if not bad:
                picks, final = (), path
                self._memo[key] = (picks, final)
                break
            candidates = self._paths_without(weights, bad)
            assert path is not None
            base = float(weights[path].sum())
            growth = [np.inf if p is None else float(weights[p].sum()) - base for p in candidates]
            j = int(np.argmax(growth))  # a bridge first, ties to the earlier edge on the path
            chain.append((key, bad[j]))
            known.add(bad[j])
            weights[bad[j]] = np.inf
            path = candidates[j]
        for key, pick in reversed(chain):
            picks = (pick, *picks)
            self._memo[key] = (picks, final)
        return self._memo[blocked]

    def rollout_cost(self, blocked: frozenset[int], checked: BoolArray) -> int:
        """R(s): checks of the rollout from a state with known-blocked ``blocked`` and (E,) ``checked``."""
        picks, final = self.blocked_phase(blocked)
        return len(picks) + (0 if final is None else int((~checked[final]).sum()))

    def q_values(
        self, blocked: frozenset[int], checked: BoolArray, candidates: IntArray, limit: float = np.inf
    ) -> FloatArray:
        """(k,) Q*(s, e) in checks for the unchecked ``candidates`` of the state (``blocked``, ``checked``).

        A blocked candidate's Q* is the better of two clairvoyant continuations: its own greedy
        rollout (only while :attr:`work` is below ``limit``; -inf: never) and following the state's
        rollout picks, one check fewer when e is one of them (module docstring).
        """
        picks, final = self.blocked_phase(blocked)
        base = self.rollout_cost(blocked, checked)
        on_final = np.zeros(self.world_free.size, dtype=bool)
        if final is not None:
            on_final[final] = True
        q = np.empty(candidates.size, dtype=np.float64)
        for j, e in enumerate(candidates.tolist()):
            if self.world_free[e]:
                q[j] = 1 + base - int(on_final[e])
                continue
            q[j] = 1 + base - int(e in picks)
            if self.work < limit:
                q[j] = min(q[j], 1 + self.rollout_cost(blocked | {e}, checked))
        return q


def fit_ridge(feats: FloatArray, regret: FloatArray, weight: FloatArray, ridge: float) -> FloatArray:
    """(F,) weighted ridge solution of ``feats @ w ~ regret`` (the bias column 0 is not penalised).

    Args:
        feats: (N, F) features.
        regret: (N,) targets, in checks.
        weight: (N,) non-negative sample weights.
        ridge: penalty per unit of total sample weight.
    """
    xw = feats * weight[:, None]
    gram = feats.T @ xw
    penalty = ridge * float(weight.sum()) * np.eye(feats.shape[1])
    penalty[0, 0] = 0.0
    return np.asarray(np.linalg.solve(gram + penalty + 1e-12 * np.eye(feats.shape[1]), xw.T @ regret))


@dataclass(frozen=True)
class DaggerSettings:
    """DAgger's budget (defaults keep training within about 30 s per authors' dataset on two cores).

    Attributes:
        rounds: learner roll-in rounds after the oracle's round 0.
        worlds_per_round: training worlds rolled in per round (new ones each round while they last).
        max_steps: visited states per episode (the episode stops there).
        beta: probability that a learner round's step follows the oracle instead.
        ridge: ridge penalty per unit sample weight.
        free_penalty: checks added to a free candidate's regret target (fail fast; module docstring).
        rollouts: give blocked candidates their own rollout (False: only the S(K) bound; cheaper).
        work_budget: Dijkstra work of all rounds (an even share each; a round stops once it is spent), in
            vertex visits (:attr:`ClairvoyantOracle.work` plus the features' Delta-len; deterministic).
    """

    rounds: int = 3
    worlds_per_round: int = 15
    max_steps: int = 40
    beta: float = 0.0
    ridge: float = 1e-3
    work_budget: float = 4e7
    free_penalty: float = 1.0
    rollouts: bool = True


def _episode(
    policy: ImitationLazySP,
    oracle: ClairvoyantOracle,
    model: ImitationModel | None,
    rng: np.random.Generator,
    settings: DaggerSettings,
    budget: float,
) -> tuple[list[tuple[FloatArray, FloatArray]], float]:
    """One roll-in (the oracle's when no model): (features (k, F), Q* (k,)) per visited state, and its work."""
    free_world = oracle.world_free
    checked = np.zeros(free_world.size, dtype=bool)
    blocked: frozenset[int] = frozenset()
    samples: list[tuple[FloatArray, FloatArray]] = []
    work, start_work, replanned = 0.0, oracle.work, True
    n = oracle.num_vertices
    for _ in range(settings.max_steps):
        found = policy.open_features()
        if found is None:
            break
        open_pos, feats = found
        if replanned:  # a new path: the features' Delta-len ran one Dijkstra over k + 1 copies
            work += (open_pos.size + 2) * (n + CALL_WORK)
        if work + oracle.work - start_work >= budget:
            break
        path = policy.proposed_path()
        assert path is not None
        edges = path[open_pos]
        limit = start_work + budget - work if settings.rollouts else -np.inf
        q = oracle.q_values(blocked, checked, edges, limit)
        q += settings.free_penalty * free_world[edges]
        samples.append((feats, q))
        use_oracle = model is None or rng.random() < settings.beta
        score = q if use_oracle or model is None else feats @ model.weights
        edge = int(edges[ranked_choice(score, feats[:, 1])])
        free = bool(free_world[edge])
        policy.observe(edge, free)
        checked[edge] = True
        replanned = not free
        if not free:
            blocked = blocked | {edge}
    return samples, work + oracle.work - start_work


def train_imitation_selector(
    graph: ExplicitGraph,
    start: int,
    goal: int,
    train_worlds: npt.ArrayLike,
    *,
    seed: int,
    train_weights: npt.ArrayLike | None = None,
    settings: DaggerSettings | None = None,
) -> ImitationModel:
    """Train the selector with DAgger against the clairvoyant oracle (module docstring).

    Episodes run only on training worlds where start and goal are connected, like the test worlds
    (in a cut-off world the clairvoyant must cut every path: long, and unlike any test episode).

    Args:
        graph: the explicit graph.
        start: start vertex.
        goal: goal vertex.
        train_worlds: (n_train, E) bool, True where edge e is free in training world h.
        seed: seed of the world order and of the beta mix.
        train_weights: (n_train,) non-negative prior weights of the worlds, or None for uniform.
        settings: DAgger's budget (None: :class:`DaggerSettings` defaults).

    Raises:
        ProblemError: bad shapes, no training world, start/goal outside the graph, bad settings.
    """
    settings = settings or DaggerSettings()
    x, prior = _training_input(graph, start, goal, train_worlds, train_weights, settings)
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    order = rng.permutation(x.shape[0])
    per_round = settings.work_budget / (settings.rounds + 1)
    data: list[tuple[FloatArray, FloatArray]] = []
    model: ImitationModel | None = None
    episodes, work, cursor = 0, 0.0, 0
    arcs, lengths = GraphArcs(graph), np.asarray(graph.lengths, dtype=np.float64)
    for _ in range(settings.rounds + 1):
        spent = 0.0
        for _ in range(settings.worlds_per_round):
            h, cursor = _next_connected(arcs, lengths, start, goal, x, order, cursor)
            if spent >= per_round or h < 0:
                break
            loo = prior.copy()
            loo[h] = 0.0  # leave the episode's own world out of its posterior
            outcomes = all_edge_outcomes(x, loo if loo.sum() > 0 else prior)
            policy = ImitationLazySP(graph, start, goal, outcomes, None)
            oracle = ClairvoyantOracle(graph, start, goal, x[h])
            samples, used = _episode(policy, oracle, model, rng, settings, per_round - spent)
            data += samples
            spent += used
            episodes += 1
        work += spent
        if data:
            feats = np.concatenate([f for f, _ in data])
            regret = np.concatenate([q - q.min() for _, q in data])
            weight = np.concatenate([np.full(q.size, 1.0 / q.size) for _, q in data])
            model = ImitationModel(fit_ridge(feats, regret, weight, settings.ridge))
    weights = np.zeros(len(FEATURE_NAMES)) if model is None else model.weights  # no state: all tie
    n_samples = float(sum(q.size for _, q in data))
    stats = dict(rounds=float(settings.rounds), episodes=float(episodes), states=float(len(data)))
    stats.update(samples=n_samples, work=work, seconds=time.perf_counter() - t0)
    return ImitationModel(weights, FEATURE_NAMES, stats)


def _training_input(
    graph: ExplicitGraph,
    start: int,
    goal: int,
    train_worlds: npt.ArrayLike,
    train_weights: npt.ArrayLike | None,
    settings: DaggerSettings,
) -> tuple[BoolArray, FloatArray]:
    """The (n, E) worlds and (n,) prior weights, checked (ProblemError naming what is wrong)."""
    if settings.rounds < 0 or settings.worlds_per_round < 1 or settings.max_steps < 1:
        raise ProblemError("DAgger needs rounds >= 0, worlds_per_round >= 1 and max_steps >= 1")
    if not 0.0 <= settings.beta <= 1.0 or not settings.ridge >= 0.0 or not settings.work_budget > 0:
        raise ProblemError("DAgger needs beta in [0, 1], ridge >= 0 and a positive work budget")
    x = np.asarray(train_worlds, dtype=bool)
    if x.ndim != 2 or x.shape[1] != graph.num_edges:
        raise ProblemError(f"training worlds must be (n_train, {graph.num_edges}) bool; got shape {x.shape}")
    if x.shape[0] == 0:
        raise ProblemError("the imitation-learned LazySP needs at least one training world")
    for label, vertex in (("start", start), ("goal", goal)):
        if not 0 <= int(vertex) < graph.num_vertices:
            raise ProblemError(f"imitation: {label} vertex {vertex} outside [0, {graph.num_vertices})")
    prior = np.ones(x.shape[0]) if train_weights is None else np.asarray(train_weights, dtype=np.float64)
    if prior.shape != (x.shape[0],) or not np.all(np.isfinite(prior) & (prior >= 0)):
        raise ProblemError(f"train_weights must be ({x.shape[0]},) finite and non-negative")
    return x, prior


def _next_connected(
    arcs: GraphArcs, lengths: FloatArray, start: int, goal: int, x: BoolArray, order: IntArray, cursor: int
) -> tuple[int, int]:
    """(the next world of ``order`` from ``cursor`` on, cyclically, with a start-goal path, or -1; new cursor)."""
    for h in order[np.arange(cursor, cursor + order.size) % order.size].tolist():
        cursor += 1
        if arcs.shortest_path(start, goal, np.where(x[h], lengths, np.inf)) is not None:
            return int(h), cursor
    return -1, cursor


def train_for_problem(problem: Problem, *, seed: int, settings: DaggerSettings | None = None) -> ImitationModel:
    """:func:`train_imitation_selector` on a problem's graph, query and training worlds.

    Raises:
        ProblemError: the problem has no graph, start/goal or training worlds.
    """
    if problem.graph is None or problem.start is None or problem.goal is None:
        raise ProblemError(f"{IMITATION_POLICY} needs the problem's graph, start and goal")
    worlds = problem.require_worlds()
    train = worlds.train_ids
    weights = None if worlds.prior is None else worlds.weights(train)
    graph, start, goal = problem.graph, problem.start, problem.goal
    return train_imitation_selector(
        graph, start, goal, worlds.X[train], seed=seed, train_weights=weights, settings=settings
    )
