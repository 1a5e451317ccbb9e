"""``python -m skidnav.realtime.reference_robot`` (:mod:`.cli`)."""

import sys

from skidnav.realtime.reference_robot.cli import main

if __name__ == "__main__":
    sys.exit(main())
