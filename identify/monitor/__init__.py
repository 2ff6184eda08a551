"""The identified model at work on a stream or a log: the generalised-momentum observer, external
torques and contact detection (:mod:`identify.monitor.observer`, :mod:`identify.monitor.contact`),
over a log block by block (:mod:`identify.monitor.log`; docs/contact-monitor.md), and payload
monitoring after every loaded motion (:mod:`identify.monitor.payload`, the paper's conclusion).

Import from the modules of this package (or from `identify` for the public API)."""
