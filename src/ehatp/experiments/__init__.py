"""Experiments on the planner: the paper's benchmarks, sweeps over many problems, random problems
and the agreement of planner, validator and executor on them, the HDDL report, and where the
example problems are."""
