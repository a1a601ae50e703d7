"""The shared widget factory wires sliders to a pure callback and redraws on change."""

import matplotlib

matplotlib.use("Agg")

import ipywidgets as widgets

from fdi_lib.errors import ModelError
from fdi_lib.plotting import figure
from fdi_lib.widgets import interactive_figure


def test_sliders_redraw_the_same_figure_with_the_new_values():
    calls = []

    def callback(a, b, fig=None):
        calls.append((a, b))
        fig, ax = figure(fig=fig)
        ax[0, 0].plot([0, 1], [a, b])
        return fig

    a = widgets.FloatSlider(value=1.0, min=0.0, max=5.0)
    b = widgets.IntSlider(value=2, min=0, max=5)
    box = interactive_figure(callback, a=a, b=b)
    assert isinstance(box, widgets.VBox)
    assert calls == [(1.0, 2)]  # drawn once at the default values
    assert a.continuous_update is False  # redraw on release only
    image = box.children[2]
    assert isinstance(image, widgets.Image) and image.format == "png"
    first = bytes(image.value)
    assert first.startswith(b"\x89PNG")
    a.value = 3.0
    b.value = 4
    assert calls[-2:] == [(3.0, 2), (3.0, 4)]
    assert (
        bytes(image.value).startswith(b"\x89PNG") and bytes(image.value) != first
    )  # the new picture


def test_a_bad_value_shows_its_error_below_the_figure():
    def callback(a, fig=None):
        if a > 2:
            raise ModelError("a: expected at most 2")
        fig, ax = figure(fig=fig)
        ax[0, 0].plot([0, 1], [a, a])
        return fig

    a = widgets.FloatSlider(value=1.0, min=0.0, max=5.0)
    box = interactive_figure(callback, a=a)
    errors = box.children[3]
    assert errors.outputs == ()
    a.value = 3.0
    assert "ModelError: a: expected at most 2" in str(errors.outputs)
    a.value = 1.5
    assert errors.outputs == ()
