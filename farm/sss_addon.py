# Run by Blender (--python this file, or --python-expr its text, followed by
# -- CHECKOUT ARGS...): imports the libsss add-on from CHECKOUT (a libsss
# checkout built with make) or, when CHECKOUT is empty, the add-on or
# extension installed in this Blender, and runs its farm task
# (addon/separable_sss/farm.py) with ARGS. The OpenJD template
# embeds this file and the Flamenco job type holds it as ADDON_BOOTSTRAP:
# the copies are kept equal (tests/farm/test_farm.py checks them).
import importlib, sys, addon_utils
args = sys.argv[sys.argv.index("--") + 1:]
checkout = args.pop(0)
if checkout:
    sys.path.insert(0, checkout + "/addon")
    name = "separable_sss"
else:
    name = next((m.__name__ for m in addon_utils.modules()
                 if m.__name__.rpartition(".")[2] == "separable_sss"), None)
    if name is None:
        sys.exit("the Separable SSS add-on is not installed in this "
                 "Blender: install it, or give a libsss checkout")
importlib.import_module(name + ".farm").main(args)
