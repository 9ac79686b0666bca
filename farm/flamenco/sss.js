// Screen-space SSS for a Blender shot on Flamenco: a job type. Put this file
// in the Manager's scripts/ folder (beside flamenco-manager) and restart the
// Manager; "Blender with Screen-Space SSS" then appears in the Flamenco
// add-on's job types. docs/farm.md has the rest.
//
// Per chunk of frames, a "blender" task renders the passes of the frames
// that have neither passes nor output yet (material SSS off, the libsss
// add-on's pipeline); then one task per frame scatters them with
// `sss --resume`, so a frame that cannot be scattered fails its own task
// with the library's message and every other frame is still written. A
// re-queued task redoes only what is missing.
//
// Output: OUTPUT_DIR/NAME_####.exr (every pass plus the SSS layer; NAME is
// the .blend's name), and OUTPUT_DIR/passes/NAME_####.exr with
// NAME_####_scene.json (what sss reads; delete them once the job is done).

const JOB_TYPE = {
    label: "Blender with Screen-Space SSS",
    description: "Renders the passes and adds screen-space subsurface scattering (libsss), frame by frame",
    settings: [
        { key: "frames", type: "string", required: true,
          eval: "f'{C.scene.frame_start}-{C.scene.frame_end}'",
          evalInfo: { showLinkButton: true, description: "Scene frame range" },
          description: "Frames to render: '47', '1-30', '3, 5-10, 47-327'" },
        { key: "chunk_size", type: "int32", default: 10, propargs: { min: 1 },
          visible: "submission",
          description: "Frames per Blender task (one Blender start per task)" },
        { key: "output_dir", type: "string", subtype: "dir_path", required: true,
          visible: "submission",
          description: "Where the frames (NAME_####.exr) and their passes (passes/) go" },
        { key: "samples", type: "int32", default: 0, propargs: { min: 0 },
          visible: "submission", description: "Cycles samples; 0 keeps the scene's" },
        { key: "method", type: "string", default: "scene", visible: "submission",
          choices: ["scene", "auto", "separable", "separable-exact", "disk", "reference"],
          description: "The library's method; scene keeps the one saved in the .blend" },
        { key: "blender", type: "string", default: "{blender}", visible: "submission",
          description: "Blender on the worker: the Manager's {blender} variable, a name on PATH or a full path" },
        { key: "sss", type: "string", default: "sss", visible: "submission",
          description: "The sss command on the worker: a name on PATH or a full path" },
        { key: "addon_checkout", type: "string", subtype: "dir_path", default: "",
          visible: "submission",
          description: "A libsss checkout on the worker (built with make) whose add-on Blender imports; empty: the add-on installed in the worker's Blender" },

        { key: "blendfile", type: "string", required: true, visible: "web",
          description: "Path of the .blend to render" },
    ],
};

// Imports the add-on (from the checkout given first after --, else the one
// installed in this Blender) and runs its farm task: farm/sss_addon.py.
const ADDON_BOOTSTRAP = `# Run by Blender (--python this file, or --python-expr its text, followed by
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
`;

function compileJob(job) {
    const settings = job.settings;
    if (!settings.output_dir) {
        throw "the job needs an output_dir";
    }
    const name = path.stem(settings.blendfile).replace(".flamenco", "");
    const passes = path.join(settings.output_dir, "passes", `${name}_####.exr`);
    const output = path.join(settings.output_dir, `${name}_####.exr`);

    for (const chunk of frameChunker(settings.frames, settings.chunk_size)) {
        const render = author.Task(`render-${chunk}`, "blender");
        const args = [
            "--python-exit-code", "1", "--python-expr", ADDON_BOOTSTRAP, "--",
            settings.addon_checkout || "", "--passes", passes, "--done", output,
            "--frames", chunk.replace(/ /g, ""),
        ];
        if (settings.samples > 0) {
            args.push("--samples", `${settings.samples}`);
        }
        if (settings.method && settings.method != "scene") {
            args.push("--method", settings.method);
        }
        render.addCommand(author.Command("blender-render", {
            exe: settings.blender || "{blender}",
            exeArgs: "{blenderArgs}",
            argsBefore: [],
            blendfile: settings.blendfile,
            args: args,
        }));
        job.addTask(render);

        for (const frame of chunkFrames(chunk)) {
            const p = atFrame(passes, frame);
            const scatter = author.Task(`sss-${frame}`, "misc");
            scatter.addCommand(author.Command("exec", {
                exe: settings.sss || "sss",
                args: [p, "-o", atFrame(output, frame),
                       "--scene", p.replace(/\.exr$/, "_scene.json"), "--resume"],
            }));
            scatter.addDependency(render);
            job.addTask(scatter);
        }
    }
}

// "1-3,7" (a frameChunker chunk) -> [1, 2, 3, 7]
function chunkFrames(chunk) {
    const frames = [];
    for (const part of `${chunk}`.replace(/ /g, "").split(",")) {
        const ends = part.split("-").map(Number);
        for (let f = ends[0]; f <= ends[ends.length - 1]; f++) {
            frames.push(f);
        }
    }
    return frames;
}

// "DIR/NAME_####.exr", 7 -> "DIR/NAME_0007.exr"
function atFrame(pattern, frame) {
    return pattern.replace("####", `${frame}`.padStart(4, "0"));
}
