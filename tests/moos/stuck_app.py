"""pTestApp whose stopping never finishes (on_stop blocks its event loop): SIGINT/SIGTERM must
end the process all the same."""

from __future__ import annotations

import sys
import time

from example_app import pTestApp


class pStuckApp(pTestApp):
    def on_stop(self):
        print("stopping", flush=True)
        time.sleep(3600)


if __name__ == "__main__":
    sys.exit(pStuckApp.main())
