"""Known-answer robots of the Rust crate (`tdcr::cases`): the paper's prototype and the
reference cases S and H (tips agreed by four independent solvers to about 2e-10 m)."""

from ._native import TIP_H, TIP_S, case_h, case_s, prototype

__all__ = ["TIP_H", "TIP_S", "case_h", "case_s", "prototype"]
