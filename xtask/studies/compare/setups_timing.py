"""pyOMA2's PoSER and PreGER on the steel frame's 15 setups, timed for `cargo xtask bench
setups` (the merge itself is `setups_fdd.steelframe`, shared with `cargo xtask
compare-setups`). Argument: the steel frame's folder. Prints one JSON document with each
merge's seconds (the records' loading excluded) and how many modes it kept.
"""

import json
import sys
from pathlib import Path

from setups_fdd import steelframe


def main():
    poser, preger = steelframe(Path(sys.argv[1]))
    print(json.dumps({
        "poser": {"seconds": poser["seconds"], "modes": len(poser["fn"])},
        "preger": {"seconds": preger["seconds"], "modes": len(preger["fn"])},
    }))


if __name__ == "__main__":
    main()
