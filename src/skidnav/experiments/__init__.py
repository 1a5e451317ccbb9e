"""skidnav.experiments."""
