"""The one search of the gap finder, for steady evidence (points, sweeps: :func:`mftyre.gaps.find_gaps`) and
dynamic evidence (time histories of runs: :func:`mftyre.gaps.dynamic.find_dynamic_gaps`) alike:

    locate -> candidates from the catalogue whose channels and variables match a finding -> refit each
    -> score on held-out evidence -> accept the best by one rule (:func:`judge`) -> verify -> add; repeat

What differs between the two kinds of evidence is only what the evidence object passed to :func:`search` does:

* ``locate()``: the findings (:class:`mftyre.gaps.locate.Finding`) of the current model: residual structure over
  the condition variables (steady), or a run's residual beyond its noise (dynamic: the variable is the run's kind,
  so a dynamic effect's variables are the run kinds it shows in);
* ``trials(tried, round)``: every candidate ``(effect, parameters, why not others)`` refitted (steady: the
  evaluator of the Magic Formula; dynamic: the wheel simulated on the runs with the measurement chain as
  nuisances) and judged, as ``[(Candidate, model)]``, best first;
* ``verify(candidate, model, m)``: ``(model, "")`` for a candidate that may be added (its values possibly pruned
  to those the data determine), or ``(model, reason)``;
* ``add(candidate, model)``: make it the current model; ``say(text)``; ``rejected``: effect -> reason;
  ``rounds``: the list the rounds are appended to (per round the :class:`Candidate` list).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["Candidate", "judge", "matches", "search"]


@dataclass
class Candidate:
    """One effect tried in one round, on either kind of evidence. ``p_value``: the training test of its
    chi-square decrease; ``held_out_p``: the held-out test (NaN where the held-out evidence allows none);
    ``score``: its held-out gain as the acceptance rule weighs it; ``significant``: accepted by :func:`judge`."""

    name: str
    parameters: list
    chi2_train_before: float = math.nan
    chi2_train_after: float = math.nan
    chi2_test_before: float = math.nan
    chi2_test_after: float = math.nan
    n_train: int = 0
    n_test: int = 0
    f_statistic: float = math.nan
    p_value: float = math.nan
    score: float = math.nan   # steady: held-out chi2 decrease x n_eff/n minus k ln(n_eff); dynamic: the decrease
    held_out_gain: float = math.nan   # relative decrease of the held-out chi2 on the effect's channels
    significant: bool = False
    values: dict = field(default_factory=dict)
    stderr: dict = field(default_factory=dict)
    note: str = ""
    n_eff: float = math.nan           # effective number of independent training residuals (from the noise)
    held_out_p: float = math.nan
    held_out_sweeps: int = 0          # steady: held-out sweeps the candidate changes (the test by whole sweeps)
    n_eff_residual: float = math.nan  # steady: the AR(1) count from the residual lacking the effect (shown)
    screened: float = math.nan        # dynamic: the linearised training decrease it was ranked by
    correlation: dict = field(default_factory=dict)  # "A~B" -> correlation of a pair too close to separate

    def to_dict(self) -> dict:
        return dict(self.__dict__)


def judge(p_train: float, level: float, p_held: float, held_level: float, gain: float, *,
          material: float = 0.0, excess: float = 0.0) -> str:
    """The acceptance rule, '' when a candidate passes, else why not: its training decrease significant at
    ``level`` (the family-wise alpha over the round's candidates), its held-out test (``p_held``, NaN: the held-out
    evidence allows none) at ``held_level``, and its held-out ``gain`` material: above ``material`` x the held-out
    chi-square the noise does not explain (``excess``; beside a large unexplained gap a tiny improvement is
    significant but names nothing) and above 0."""
    if not p_train < level:
        return f"training decrease not significant (p {p_train:.2g} >= {level:.2g})"
    if math.isfinite(p_held) and not p_held < held_level:
        return f"held-out decrease not significant (p {p_held:.2g} >= {held_level:.2g})"
    need = material * max(excess, 0.0)
    if not gain > need:
        if material:
            return (f"explains {100 * gain / max(excess, 1e-300):.1f} % of the held-out chi-square above the noise "
                    f"(needs {100 * material:g} %)")
        return f"no held-out gain beyond the penalty for its parameters (score {gain:.3g})"
    return ""


def matches(effect, findings) -> bool:
    """Whether a finding is in one of ``effect``'s channels and along one of its variables."""
    return any(f.channel in effect.channels and any(v in effect.variables for v in f.variables) for f in findings)


def search(evidence, candidates: dict, findings: list, max_effects: int) -> None:
    """Rounds until no finding is left, none is explained, or ``max_effects`` are added; ``candidates``: effect name
    -> (effect, parameters the data determine, {parameter: why not}), emptied of what is added or rejected."""
    rounds, added = evidence.rounds, 0
    while findings and added < max_effects:
        tried = [t for t in candidates.values() if matches(t[0], findings)]
        if not tried:
            evidence.say("no catalogue effect matches the findings")
            break
        results = evidence.trials(tried, len(rounds) + 1)
        rounds.append([cand for cand, _ in results])
        best = None
        for cand, new in results:
            if not cand.significant:
                continue
            new, reason = evidence.verify(cand, new, len(tried))
            if reason:
                cand.significant = False
                cand.note = "; ".join(x for x in (cand.note, "rejected: " + reason) if x)
                evidence.rejected[cand.name] = reason
                del candidates[cand.name]
                evidence.say(f"rejected {cand.name}: {reason}")
                continue
            best = cand, new
            break
        if best is None:
            evidence.say("no candidate is significant on the held-out data"
                         + (" and passes verification" if evidence.rejected else ""))
            break
        evidence.add(*best)
        del candidates[best[0].name]
        added += 1
        findings = evidence.locate()
