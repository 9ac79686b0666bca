"""Failures injected from the test side, so that the add-on holds no test
hooks: each wraps one of the add-on's own functions for one test (pytest's
monkeypatch, or patch() in a Blender started by a test), and the add-on
then meets a real failure there. Blender itself runs unchanged.

The one hook left in the add-on is SSS_TEST_FAIL=cancel (pipeline.py): a
render cancelled with Esc cannot happen headless without a mock of
Blender's render operator."""
from contextlib import contextmanager


def fail_after_render(monkeypatch, pipeline):
    """Render with SSS renders, then saving its passes fails: an error
    inside the switched-off scene."""
    def save_passes(scene, path):
        raise pipeline.SSSError("injected failure after the render")
    monkeypatch.setattr(pipeline, "save_passes", save_passes)


def library_refuses(monkeypatch, pipeline):
    """The job Render with SSS prepares asks the library for radius scale
    -1, which the library refuses with its own message."""
    prepare = pipeline.prepare_render

    def refused(context):
        job = prepare(context)
        job.radius_scale = -1.0
        return job
    monkeypatch.setattr(pipeline, "prepare_render", refused)


def _without_diffuse_color(switched_off):
    @contextmanager
    def switched(scene, *args, **kwargs):
        with switched_off(scene, *args, **kwargs) as undo:
            for layer in scene.view_layers:  # a real missing pass
                layer.use_pass_diffuse_color = False
            yield undo
    return switched


def drop_a_pass(monkeypatch, render_flow):
    """The render flow's scene renders without the Diffuse Color pass the
    library needs."""
    monkeypatch.setattr(render_flow, "switched_off",
                        _without_diffuse_color(render_flow.switched_off))


def patch(render_flow):
    """drop_a_pass for a whole Blender process (started with
    --python-expr by a test), without pytest."""
    render_flow.switched_off = _without_diffuse_color(
        render_flow.switched_off)
