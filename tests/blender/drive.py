"""Runs a Blender script's steps on a timer (timers fire only with a window): shared by the
windowed test scripts and tools/blender_screenshot.py, so it needs nothing but bpy."""

import os
import sys

import bpy


def drive(steps, interval=0.1, handle=None):
    """Runs the generator `steps` one step per timer tick (timers fire only with a window) and
    quits Blender when it ends, removing the draw handler `handle`; a Python error prints its
    traceback and ends Blender with status 1 (a timer's exceptions would only be printed)."""
    def tick():
        try:
            next(steps)
        except StopIteration:
            if handle is not None:
                bpy.types.SpaceView3D.draw_handler_remove(handle, 'WINDOW')
            bpy.ops.wm.quit_blender()
            return None
        except Exception:
            import traceback
            traceback.print_exc()
            sys.stdout.flush()
            os._exit(1)
        return interval

    bpy.app.timers.register(tick, first_interval=0.5)
