"""The hardware-in-the-loop study: trials on the robot (real or simulated), their summaries and
tables."""
