/**
 * Where the demo keeps its S7-1200's certificate between runs (`npm start`): a directory of the user's own, outside
 * the package, as each platform keeps an application's state: $XDG_STATE_HOME (else ~/.local/state) on Linux and
 * other POSIX systems (XDG Base Directory Specification 0.8), ~/Library/Application Support on macOS, %LOCALAPPDATA%
 * on Windows. A flow that pinned the demo's s7plus:// URL still trusts it after a restart (issue #31).
 */
import * as os from 'node:os';
import * as path from 'node:path';

/** The demo's certificate directory for this user (`env`, `platform` and `home` are the process's unless given). */
export function demoCertificateDir(
  env: NodeJS.ProcessEnv = process.env,
  platform: NodeJS.Platform = process.platform,
  home = os.homedir(),
): string {
  const base =
    platform === 'win32'
      ? (env.LOCALAPPDATA ?? path.win32.join(home, 'AppData', 'Local'))
      : platform === 'darwin'
        ? path.posix.join(home, 'Library', 'Application Support')
        : env.XDG_STATE_HOME && path.posix.isAbsolute(env.XDG_STATE_HOME)
          ? env.XDG_STATE_HOME
          : path.posix.join(home, '.local', 'state');
  return (platform === 'win32' ? path.win32 : path.posix).join(base, 'plcwire', 'demo-tls');
}
