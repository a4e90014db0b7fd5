"""Case files (input) and result files (output)."""

from slipcycle.io.case import Case, CaseError, Section, parse_case_text, read_case
from slipcycle.io.results import RunOutputs, write_outputs

__all__ = ["Case", "CaseError", "RunOutputs", "Section", "parse_case_text", "read_case",
           "write_outputs"]
