"""What every script run as `blender -b --python SCRIPT -- ARGS` shares:
its own arguments (those after `--`) and an exit status Blender passes on
(`--python-exit-code 1`): a traceback and status 1 for any error, argparse's
own status for bad arguments."""
import sys
import traceback


def script_argv():
    """The arguments after Blender's `--`; none without it."""
    return sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []


def run_main(main):
    try:
        main()
    except SystemExit:
        raise
    except Exception:
        traceback.print_exc()
        sys.exit(1)
