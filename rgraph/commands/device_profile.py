"""``rgraph device-profile``: capture the device's limits and memory requirements into JSON."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("device-profile", help="capture a device profile (limits, memory requirements)")
    parser.add_argument("-o", "--output", type=Path, help="write the profile here (default: stdout)")
    parser.add_argument("--device", type=int, default=None, help="physical device index")
    parser.add_argument("--name", default=None, help="profile name (default: derived from the device)")
    parser.add_argument("--formats", default=None, help="comma-separated formats (default: all supported)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rgraph import formats
    from rgraph.vk.device import create_device
    from rgraph.vk.errors import VulkanUnavailable
    from rgraph.vk.instance import create_instance
    from rgraph.vk.profile_capture import ProfileCaptureError, capture_profile

    fmts = [f.strip() for f in args.formats.split(",") if f.strip()] if args.formats else None
    unknown = [f for f in fmts or () if not _known_format(formats, f)]
    if unknown:
        print(f"rgraph: error: --formats: unknown format {', '.join(unknown)}", file=sys.stderr)
        return 2
    try:
        instance = create_instance(validate=False)
    except VulkanUnavailable as exc:
        print(f"rgraph: error: {exc}", file=sys.stderr)
        return 1
    device = None
    try:
        from rgraph.vk.device import choose_physical_device, list_physical_devices
        from rgraph.vk.rt_device import supported

        physical = choose_physical_device(list_physical_devices(instance), args.device)
        device = create_device(instance, args.device, ray_tracing=supported(physical.handle))
        name = args.name or ("lavapipe" if "llvmpipe" in device.name else device.name.split()[0].lower())
        profile = capture_profile(device, name, fmts)
    except VulkanUnavailable as exc:
        print(f"rgraph: error: {exc}", file=sys.stderr)
        return 1
    except ProfileCaptureError as exc:
        print(f"rgraph: error: cannot capture a profile of {device.name if device else 'the device'}: {exc}",
              file=sys.stderr)
        return 1
    finally:
        if device is not None:
            device.destroy()
        instance.destroy()
    text = json.dumps(profile, indent=1, sort_keys=True) + "\n"
    if args.output:
        args.output.write_text(text)
        ruled = sum(1 for f in profile["formats"].values() if f["rule"])
        print(f"rgraph: wrote {args.output}: {len(profile['formats'])} formats, {ruled} with a verified rule",
              file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _known_format(formats, name: str) -> bool:  # noqa: ANN001 - the rgraph.formats module
    try:
        formats.lookup(name)
    except KeyError:
        return False
    return True
