import os

from hypothesis import settings

# CI explores the same examples on every run, so a red build always reproduces; developers'
# runs keep drawing new ones. No deadline: a 2-core CI machine under load is slow, not wrong.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")
