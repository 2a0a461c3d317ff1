"""A Python sidecar: the human (an operator at base) has its own small task, and what the
rover sends is hidden from it until told."""

from ehatp import Domain

SIDECAR = {
    "observability": {"hidden": ["sent"]},
    "other": {"agenda": ["log"]},
}


def customize(d: Domain) -> None:
    logged = d.predicate("logged")
    d.human.action("log", pre=~logged(), effects=[logged()])
