"""What the models see: simulated scenes (scenes/) and the physics they build on (physics/),
users' files (readers/), the tables and recording sets both become, preprocessing, splits and the
datamodules. Imports only common/ below it (tests/test_house.py)."""
