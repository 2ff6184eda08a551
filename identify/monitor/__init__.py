"""The identified model at work: the generalised-momentum observer, external torques and contact
detection (:mod:`identify.monitor.observer`, :mod:`identify.monitor.contact`), over a log block by
block (:mod:`identify.monitor.log`); docs/contact-monitor.md."""
