"""Scores of simulated against measured vibration (layer L3, DESIGN §6).

:func:`score_runs` compares two runs' PSDs over a band (log-spectral distance, level difference,
1/3-octave band level errors, matched peaks, shape correlation), each with a significance flag
against the estimation uncertainty; :func:`scores_to_json` gives the JSON of the CLI.
"""

from fivid.score.export import scores_to_json
from fivid.score.runs import score_runs

__all__ = ["score_runs", "scores_to_json"]
