/**
 * Our message catalogs as Node-RED itself loads them: the i18n module of the
 * Node-RED of this run (@node-red/util, which configures i18next with the
 * `__name__` interpolation), each node file's catalog registered under its
 * node set id the way the registry does. The test helper makes `RED._` the
 * identity; `withCatalog` gives a node module a `RED._` that translates.
 */
import * as fs from 'node:fs';
import * as path from 'node:path';
import { RED_PATH, ROOT } from './support';

export const LOCALES = ['en-US', 'de', 'zh-CN'] as const;
export type Locale = (typeof LOCALES)[number];

const pkg = JSON.parse(fs.readFileSync(path.join(ROOT, 'package.json'), 'utf8'));
/** Node type → its .js file, from package.json's node-red.nodes. */
export const NODE_FILES: Record<string, string> = pkg['node-red'].nodes;
const LOCALES_DIR = path.join(ROOT, 'nodes', 'locales');

/** The namespace Node-RED gives a node file's catalog: the node set id, `<module>/<set name>`. */
export function namespaceOf(type: string): string {
  return `${pkg.name}/${type}`;
}

/** The catalog file of a node type, e.g. read.json for plcwire-read. */
export function catalogFile(type: string): string {
  return path.basename(NODE_FILES[type]!).replace(/\.js$/, '.json');
}

/** A catalog as stored, parsed. */
export function rawCatalog(locale: Locale, type: string): any {
  return JSON.parse(fs.readFileSync(path.join(LOCALES_DIR, locale, catalogFile(type)), 'utf8'));
}

/** Every catalog file in nodes/locales, with its path relative to the root. */
export function catalogFiles(): string[] {
  return fs
    .readdirSync(LOCALES_DIR)
    .flatMap((lang) => fs.readdirSync(path.join(LOCALES_DIR, lang)).map((f) => path.join('nodes', 'locales', lang, f)))
    .sort();
}

export type Translate = (key: string, params?: object) => string;

export interface Catalogs {
  /** Node-RED's runtime translation (`RED._` of a node of `type`) fixed to `locale`. */
  translator(locale: Locale, type: string): Translate;
}

let loaded: Promise<Catalogs> | undefined;

/** Registers our catalogs with the runtime's i18n once per process and loads every locale. */
export function loadCatalogs(): Promise<Catalogs> {
  loaded ??= (async () => {
    const utilPath = require.resolve('@node-red/util', { paths: [path.dirname(RED_PATH)] });
    const { i18n } = require(utilPath);
    i18n.init({ lang: 'en-US' }); // a no-op when the runtime initialised it already
    for (const type of Object.keys(NODE_FILES)) await i18n.registerMessageCatalog(namespaceOf(type), LOCALES_DIR, catalogFile(type));
    await i18n.i.loadLanguages([...LOCALES]);
    return {
      translator(locale, type) {
        const t = i18n.i.getFixedT(locale);
        const ns = namespaceOf(type);
        // As the registry's node API does: a key without a namespace is in the node's own catalog.
        return (key, params) => t(key.includes(':') ? key : `${ns}:${key}`, params);
      },
    };
  })();
  return loaded;
}

/** A node module (a function of RED) that sees `translate` as RED._, everything else as the helper gives it. */
export function withCatalog(module: (red: any) => unknown, translate: Translate): (red: any) => unknown {
  return (red: any) => module(new Proxy(red, { get: (target, key) => (key === '_' ? translate : Reflect.get(target, key)) }));
}
