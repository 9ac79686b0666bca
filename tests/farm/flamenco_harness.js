// Compiles a Flamenco job type the way a Flamenco Manager does, without the
// Manager: the job type's compileJob(job) runs against our own
// implementation of the job compiler's documented globals (author.Task,
// author.Command, task.addCommand, task.addDependency, job.addTask,
// job.settings with the job type's defaults, frameChunker, path, print),
// and the Manager's two-way variables ({blender}, {blenderArgs}) are
// replaced in every command parameter. Prints the tasks as JSON:
//
//   node flamenco_harness.js JOB_TYPE.js SETTINGS_JSON VARIABLES_JSON
//   -> {"label": ..., "tasks": [{"name", "type", "commands":
//       [{"name", "parameters"}], "dependencies": [task names]}]}
//
// This tests a job type's output, not a Flamenco Manager or Worker.
"use strict";
const fs = require("fs");
const nodePath = require("path").posix;
const vm = require("vm");

function fail(message) {
    process.stderr.write(`flamenco_harness: ${message}\n`);
    process.exit(1);
}

// Flamenco's frame ranges: "1-30", "3, 5-10, 47"; chunks of chunkSize
// frames, each written back as ranges ("1-10", "3,5-6").
function parseFrames(text) {
    const frames = [];
    for (const part of `${text}`.split(",")) {
        const m = part.trim().match(/^(-?\d+)(?:\s*-\s*(-?\d+))?$/);
        if (!m) fail(`bad frame range "${text}"`);
        const lo = Number(m[1]), hi = m[2] === undefined ? lo : Number(m[2]);
        if (hi < lo) fail(`bad frame range "${text}"`);
        for (let f = lo; f <= hi; f++) frames.push(f);
    }
    return frames;
}

function rangesText(frames) {
    const parts = [];
    let start = 0;
    for (let i = 1; i <= frames.length; i++) {
        if (i === frames.length || frames[i] !== frames[i - 1] + 1) {
            const a = frames[start], b = frames[i - 1];
            parts.push(a === b ? `${a}` : `${a}-${b}`);
            start = i;
        }
    }
    return parts.join(",");
}

function frameChunker(frames, chunkSize) {
    const size = Number(chunkSize);
    if (!(size >= 1)) fail(`bad chunk size ${chunkSize}`);
    const all = parseFrames(frames);
    const chunks = [];
    for (let i = 0; i < all.length; i += size) {
        chunks.push(rangesText(all.slice(i, i + size)));
    }
    return chunks;
}

class Task {
    constructor(name, type) {
        this.name = name;
        this.type = type;
        this.commands = [];
        this.dependencies = [];
    }
    addCommand(command) {
        if (!(command instanceof Command)) fail(`${this.name}: addCommand needs an author.Command`);
        this.commands.push(command);
    }
    addDependency(task) {
        if (!(task instanceof Task)) fail(`${this.name}: addDependency needs an author.Task`);
        this.dependencies.push(task);
    }
}

class Command {
    constructor(name, parameters) {
        this.name = name;
        this.parameters = parameters;
    }
}

function main() {
    const [scriptPath, settingsJson, variablesJson] = process.argv.slice(2);
    if (!scriptPath || !settingsJson) {
        fail("usage: node flamenco_harness.js JOB_TYPE.js SETTINGS_JSON [VARIABLES_JSON]");
    }
    const given = JSON.parse(settingsJson);
    const variables = JSON.parse(variablesJson || "{}");
    const tasks = [];
    const printed = [];
    const context = vm.createContext({
        author: {
            Task: (name, type) => new Task(name, type),
            Command: (name, parameters) => new Command(name, parameters),
        },
        frameChunker: frameChunker,
        path: {
            join: (...parts) => nodePath.join(...parts),
            dirname: (p) => nodePath.dirname(p),
            basename: (p) => nodePath.basename(p),
            stem: (p) => nodePath.basename(p, nodePath.extname(p)),
        },
        print: (...args) => printed.push(args.map(String).join(" ")),
        alert: (...args) => printed.push(args.map(String).join(" ")),
    });
    // The Manager loads the script, reads JOB_TYPE and calls compileJob.
    vm.runInContext(fs.readFileSync(scriptPath, "utf8") +
                    "\n;globalThis.JOB_TYPE = JOB_TYPE;", context,
                    { filename: scriptPath });
    const jobType = context.JOB_TYPE;
    if (typeof context.compileJob !== "function") fail(`${scriptPath} has no compileJob(job)`);
    const keys = new Set(jobType.settings.map((s) => s.key));
    for (const key of Object.keys(given)) {
        if (!keys.has(key)) fail(`unknown setting "${key}"`);
    }
    const settings = {};
    for (const s of jobType.settings) {
        const value = key => given[key] !== undefined ? given[key] : s.default;
        settings[s.key] = value(s.key);
        if (s.required && (settings[s.key] === undefined || settings[s.key] === "")) {
            fail(`setting "${s.key}" is required`);
        }
        if (s.choices && settings[s.key] !== undefined && !s.choices.includes(settings[s.key])) {
            fail(`setting "${s.key}": "${settings[s.key]}" is not one of ${s.choices.join(", ")}`);
        }
    }
    const job = {
        name: "test job",
        created: new Date(),
        settings: settings,
        addTask: (task) => {
            if (!(task instanceof Task)) fail("addTask needs an author.Task");
            tasks.push(task);
        },
    };
    context.compileJob(job);

    // The Manager's variables: {name} in any string parameter.
    const expand = (value) => {
        if (typeof value === "string") {
            return value.replace(/\{([A-Za-z_]+)\}/g, (m, name) =>
                Object.prototype.hasOwnProperty.call(variables, name) ? variables[name] : m);
        }
        if (Array.isArray(value)) return value.map(expand);
        return value;
    };
    const names = new Set();
    for (const t of tasks) {
        if (names.has(t.name)) fail(`two tasks are named "${t.name}"`);
        names.add(t.name);
    }
    for (const t of tasks) {
        for (const d of t.dependencies) {
            if (!tasks.includes(d)) fail(`${t.name} depends on a task the job does not have`);
        }
    }
    const out = {
        label: jobType.label,
        printed: printed,
        tasks: tasks.map((t) => ({
            name: t.name,
            type: t.type,
            dependencies: t.dependencies.map((d) => d.name),
            commands: t.commands.map((c) => ({
                name: c.name,
                parameters: Object.fromEntries(Object.entries(c.parameters)
                    .map(([k, v]) => [k, expand(v)])),
            })),
        })),
    };
    process.stdout.write(JSON.stringify(out, null, 1) + "\n");
}

main();
