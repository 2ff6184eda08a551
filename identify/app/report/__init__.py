"""Self-contained HTML reports: one page builder (summary first, then sections) for every command.

``page`` holds the building blocks (:class:`Page`, :class:`Summary`, :class:`Section`,
:class:`Table`, :class:`Figure`, :class:`Text`) and :func:`write_page`; ``summary`` the shared
verdict pieces (held-out thresholds, flags, next steps); ``tables`` the tables built from the JSON
records; ``identify_page`` and ``payload_pages`` the reports of ``identify``, ``payload`` and
``gains``, ``excite_page`` that of an excitation trajectory; ``writers`` adds the figures and
writes them. Another command builds its own :class:`Page` from the same blocks.
"""
from .figures import (figure, parameter_figure, residual_figure, torque_figure,  # noqa: F401
                      trajectory_figure)
from .excite_page import excite_page  # noqa: F401
from .identify_page import identify_page, identify_summary  # noqa: F401
from .page import Cell, Column, Figure, Page, Section, Summary, Table, Text, render, write_page  # noqa: F401
from .payload_pages import gains_page, payload_page  # noqa: F401
from .summary import as_flag, flag, next_steps  # noqa: F401
