"""The simulated robot: the firmware-like robot model (:mod:`.robot`) and the TCP server that
speaks the wire protocol for it (:mod:`.server`, in lockstep :mod:`.lockstep`), over the byte
channels and listener of :mod:`.transport`."""
