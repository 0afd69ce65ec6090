/**
 * Editor code the plcwire dialogs share (connection, read, write, heartbeat,
 * control): deploy-time validation with the runtime's parser, the tag table,
 * address hints. Node-RED serves it at
 * resources/@plcwire/node-red-siemens/plcwire-editor.js; each node's .html
 * loads it with a <script src>, and the editor runs a node's inline scripts
 * only once it has loaded. Loaded by several dialogs, it runs once: a second
 * run would forget the parser's answers the first one collected.
 */
(function () {
  'use strict';
  if (window.plcwireEditor) return;
  var editor = (window.plcwireEditor = {});

  /** The connection config node chosen in a dialog, or null when none (or "add new…"). */
  editor.connectionNode = function (connectionId) {
    return connectionId && connectionId !== '_ADD_' ? RED.nodes.node(connectionId) : null;
  };

  /** The URL of a connection config node chosen in a dialog, or '' when none. */
  editor.urlOf = function (connectionId) {
    var c = editor.connectionNode(connectionId);
    return c ? c.url || '' : '';
  };

  /** Asks the runtime (the library's own parser) about addresses: callback(results) with { address: { ok, type, message } }. */
  editor.validate = function (url, addresses, callback) {
    $.ajax({
      url: 'plcwire/validate',
      type: 'POST',
      contentType: 'application/json',
      data: JSON.stringify({ url: url || undefined, addresses: addresses }),
      success: function (res) {
        callback((res && res.results) || {}, res && res.url);
      },
      error: function () {
        callback({});
      },
    });
  };

  // --- deploy-time validation: the nodes' validate functions, with the library's parser ---
  // A validate function must answer at once, the parser runs in the runtime: the functions answer from
  // what the runtime said before, ask about what it has not been asked yet, and every plcwire node is
  // validated again when the answers arrive (so the red triangle appears a moment after a flow loads).

  var answers = {}; // url → { '': the URL's answer, address: the address's answer }
  var wanted = {}; // url → { address: true }, for the next question
  var asking;

  function answerOf(url, address) {
    var known = answers[url] && answers[url][address];
    if (known) return known;
    (wanted[url] = wanted[url] || {})[address] = true;
    if (!asking) asking = setTimeout(ask, 0); // one question per URL for everything validated in this turn
    return undefined;
  }

  function ask() {
    asking = undefined;
    var batch = wanted;
    wanted = {};
    Object.keys(batch).forEach(function (url) {
      var addresses = Object.keys(batch[url]).filter(Boolean);
      $.ajax({
        url: 'plcwire/validate',
        type: 'POST',
        contentType: 'application/json',
        data: JSON.stringify({ url: url || undefined, addresses: addresses }),
        success: function (res) {
          var known = (answers[url] = answers[url] || {});
          known[''] = (res && res.url) || { ok: true };
          // With an invalid URL there are no address answers: the connection is what is wrong.
          addresses.forEach(function (a) {
            known[a] = (res && res.results && res.results[a]) || { ok: true };
          });
          revalidate();
        },
        // No answer (runtime gone): nothing is cached, the next validation asks again.
      });
    });
  }

  /** Validates every plcwire node again (config nodes first: their users' validity depends on them). */
  function revalidate() {
    var redraw = false;
    var configs = false;
    function again(n) {
      var before = n.valid + JSON.stringify(n.validationErrors || []);
      RED.editor.validateNode(n);
      if (before === n.valid + JSON.stringify(n.validationErrors || [])) return false;
      n.dirty = true;
      redraw = true;
      return true;
    }
    RED.nodes.eachConfig(function (n) {
      if (n.type === 'plcwire-connection' && again(n)) configs = true;
    });
    RED.nodes.eachNode(function (n) {
      if (n.type.indexOf('plcwire-') === 0) again(n);
    });
    if (configs && RED.sidebar.config && RED.sidebar.config.refresh) RED.sidebar.config.refresh();
    if (redraw) RED.view.redraw(true);
  }

  /** The parser's objection to a URL, or undefined (also while the answer is on its way). */
  editor.urlProblem = function (url) {
    var answer = answerOf(String(url == null ? '' : url).trim(), '');
    return answer && !answer.ok ? answer.message : undefined;
  };

  /** The parser's objections to addresses with the URL of connection `connectionId`. */
  function addressProblems(connectionId, addresses) {
    var url = editor.urlOf(connectionId);
    var urlAnswer = answerOf(url, '');
    var out = [];
    addresses.forEach(function (a) {
      var answer = a ? answerOf(url, a) : undefined;
      if (urlAnswer && urlAnswer.ok && answer && !answer.ok) out.push(answer.message);
    });
    return out;
  }

  /** The name a row is known by: its name, or its address when it has none. */
  function rowName(row) {
    return String((row && row.name) || '').trim() || String((row && row.address) || '').trim();
  }

  /** Names given to more than one row. */
  editor.duplicateNames = function (rows) {
    var count = {};
    (rows || []).forEach(function (r) {
      var n = rowName(r);
      if (n) count[n] = (count[n] || 0) + 1;
    });
    return Object.keys(count).filter(function (n) {
      return count[n] > 1;
    });
  };

  /** For a node's `tags` validate: true, or what is wrong (names used twice, addresses the parser refuses). */
  editor.validateTags = function (node, tags) {
    if (!Array.isArray(tags)) return false;
    var problems = editor.duplicateNames(tags).map(function (n) {
      return node._('plcwire.editor.duplicateName', { name: n });
    });
    problems = problems.concat(
      addressProblems(
        node.connection,
        tags.map(function (t) {
          return String((t && t.address) || '').trim();
        }),
      ),
    );
    return problems.length ? problems : true;
  };

  /** For a node's single-address validate (heartbeat): true, or the parser's objection. An empty address is valid. */
  editor.validateAddress = function (node, address) {
    var problems = addressProblems(node.connection, [String(address == null ? '' : address).trim()]);
    return problems.length ? problems[0] : true;
  };

  /**
   * One address input: validates it as it is typed and shows the type or the
   * problem in `hint`. Returns { check, dispose }; dispose (on Done and Cancel)
   * stops a pending validation, which would otherwise outlive the dialog.
   */
  editor.watchAddress = function (input, hint, urlOf) {
    var timer;
    var closed = false;
    function check() {
      if (closed) return;
      var address = String(input.val() || '').trim();
      input.removeClass('plcwire-invalid');
      hint.text('').removeClass('plcwire-bad');
      if (!address) return;
      editor.validate(urlOf(), [address], function (results) {
        var r = results[address];
        if (closed || !r) return;
        if (r.ok) hint.text(r.type + (r.count > 1 ? '[' + r.count + ']' : ''));
        else {
          input.addClass('plcwire-invalid');
          hint.text(r.message).addClass('plcwire-bad');
        }
      });
    }
    input.on('input change', function () {
      clearTimeout(timer);
      timer = setTimeout(check, 300);
    });
    check();
    return {
      check: check,
      dispose: function () {
        closed = true;
        clearTimeout(timer);
      },
    };
  };

  /** Asks the runtime to read CSV text into tags (the library's importer, with the connection's parser). */
  function importCsv(url, text, callback) {
    $.ajax({
      url: 'plcwire/csv',
      type: 'POST',
      contentType: 'application/json',
      data: JSON.stringify({ url: url || undefined, text: text }),
      success: function (res) {
        callback((res && res.tags) || [], (res && res.problems) || []);
      },
      error: function (xhr) {
        RED.notify(String((xhr && xhr.statusText) || 'error'), 'error');
      },
    });
  }

  function csvField(text) {
    text = String(text == null ? '' : text);
    return /[",;\t\r\n]|^\s|\s$/.test(text) ? '"' + text.replace(/"/g, '""') + '"' : text;
  }

  /** The table as CSV, in the form the importer reads back (lib/tags/table.ts, tagsToCsv). */
  editor.tagsToCsv = function (tags) {
    return (
      ['name,address']
        .concat(
          tags.map(function (t) {
            return csvField(t.name) + ',' + csvField(t.address);
          }),
        )
        .join('\r\n') + '\r\n'
    );
  };

  /**
   * The tag table of the read and write dialogs: an editableList of name/address
   * rows with add/remove, validation against the chosen connection (addresses
   * by the runtime's parser, names used twice), CSV import (replace or append)
   * and export. Returns { value(): [{ name, address }], revalidate(), dispose() };
   * dispose on Done and Cancel, so no validation runs after the dialog closed.
   */
  editor.tagTable = function (container, tags, urlOf, t) {
    var toolbar = $('<div class="plcwire-tags-toolbar">').insertBefore(container);
    var importButton = $('<button type="button" class="red-ui-button red-ui-button-small"><i class="fa fa-upload"></i> </button>').appendTo(
      toolbar,
    );
    importButton.append(document.createTextNode(t('plcwire.editor.importCsv')));
    var exportButton = $(
      '<button type="button" class="red-ui-button red-ui-button-small"><i class="fa fa-download"></i> </button>',
    ).appendTo(toolbar);
    exportButton.append(document.createTextNode(t('plcwire.editor.exportCsv')));
    var file = $('<input type="file" accept=".csv,text/csv,text/plain" style="display:none">').appendTo(toolbar);
    var timer;
    var closed = false;

    function rowOf(item) {
      return {
        name: String(item.find('.plcwire-tag-name').val() || '').trim(),
        address: String(item.find('.plcwire-tag-address').val() || '').trim(),
      };
    }

    function markDuplicates(items) {
      var rows = items.map(rowOf);
      var twice = editor.duplicateNames(rows);
      items.forEach(function (item, i) {
        var name = rowName(rows[i]);
        var duplicate = twice.indexOf(name) >= 0;
        item
          .find('.plcwire-tag-name')
          .toggleClass('plcwire-invalid', duplicate)
          .attr('title', duplicate ? t('plcwire.editor.duplicateName', { name: name }) : '');
      });
    }

    function validateAll() {
      if (closed) return;
      var items = [];
      container.editableList('items').each(function () {
        items.push($(this));
      });
      markDuplicates(items);
      var addresses = items
        .map(function (r) {
          return rowOf(r).address;
        })
        .filter(Boolean);
      if (!addresses.length) return;
      editor.validate(urlOf(), addresses, function (results) {
        if (closed) return;
        items.forEach(function (r) {
          var input = r.find('.plcwire-tag-address');
          var type = r.find('.plcwire-tag-type');
          var res = results[String(input.val() || '').trim()];
          input.removeClass('plcwire-invalid');
          type.removeClass('plcwire-invalid-text').text('').attr('title', '');
          if (!res) return;
          if (res.ok) type.text(res.type + (res.count > 1 ? '[' + res.count + ']' : ''));
          else {
            input.addClass('plcwire-invalid');
            type.addClass('plcwire-invalid-text').text(t('plcwire.editor.invalid')).attr('title', res.message);
          }
        });
      });
    }
    function later() {
      if (closed) return;
      clearTimeout(timer);
      timer = setTimeout(validateAll, 300);
    }

    container.css({ 'min-height': '150px', 'min-width': '450px' }).editableList({
      addButton: t('plcwire.editor.addTag'),
      removable: true,
      sortable: true,
      height: 'auto',
      addItem: function (row, index, data) {
        var line = $('<div class="plcwire-tag-row">').appendTo(row);
        $('<input type="text" class="plcwire-tag-name">')
          .attr('placeholder', t('plcwire.editor.tagName'))
          .val(data.name || '')
          .appendTo(line)
          .on('input change', later);
        $('<input type="text" class="plcwire-tag-address">')
          .attr('placeholder', t('plcwire.editor.tagAddress'))
          .val(data.address || '')
          .appendTo(line)
          .on('input change', later);
        $('<span class="plcwire-tag-type">').appendTo(line);
        later();
      },
      removeItem: later,
    });
    (tags || []).forEach(function (tag) {
      container.editableList('addItem', tag);
    });

    function addImported(imported, problems, replace) {
      if (closed) return;
      if (replace) container.editableList('empty');
      imported.forEach(function (tag) {
        container.editableList('addItem', tag);
      });
      later();
      RED.notify(t('plcwire.editor.imported', { count: imported.length }), { type: 'success', timeout: 3000 });
      if (problems.length) {
        // Names and addresses come from the file: text nodes, never HTML.
        var list = $('<div>').append($('<p>').text(t('plcwire.editor.importProblems')));
        var ul = $('<ul>').appendTo(list);
        problems.slice(0, 10).forEach(function (p) {
          $('<li>')
            .text(t('plcwire.editor.line', { line: p.line, message: p.message }))
            .appendTo(ul);
        });
        if (problems.length > 10) $('<li>').text('…').appendTo(ul);
        RED.notify(list, { type: 'warning', timeout: 10000 });
      }
    }

    /** Into an empty table at once; into one with rows, as the user chooses: replace them or append. */
    function chooseAndAdd(imported, problems) {
      if (closed) return;
      if (api.value().length === 0 || imported.length === 0) return addImported(imported, problems, false);
      var choice = RED.notify(t('plcwire.editor.importChoice', { count: imported.length }), {
        modal: true,
        fixed: true,
        type: 'compact',
        buttons: [
          {
            id: 'plcwire-import-cancel',
            text: RED._('common.label.cancel'),
            click: function () {
              choice.close();
            },
          },
          {
            id: 'plcwire-import-append',
            text: t('plcwire.editor.append'),
            click: function () {
              choice.close();
              addImported(imported, problems, false);
            },
          },
          {
            id: 'plcwire-import-replace',
            text: t('plcwire.editor.replace'),
            class: 'primary',
            click: function () {
              choice.close();
              addImported(imported, problems, true);
            },
          },
        ],
      });
    }

    importButton.on('click', function () {
      file.val('');
      file.trigger('click');
    });
    file.on('change', function () {
      var f = this.files && this.files[0];
      if (!f) return;
      var reader = new FileReader();
      reader.onload = function () {
        if (!closed) importCsv(urlOf(), String(reader.result || ''), chooseAndAdd);
      };
      reader.readAsText(f);
    });
    exportButton.on('click', function () {
      var blob = new Blob([editor.tagsToCsv(api.value())], { type: 'text/csv' });
      var a = document.createElement('a');
      a.href = URL.createObjectURL(blob);
      a.download = 'plcwire-tags.csv';
      document.body.appendChild(a);
      a.click();
      setTimeout(function () {
        URL.revokeObjectURL(a.href);
        a.remove();
      }, 0);
    });

    var api = {
      value: function () {
        var out = [];
        container.editableList('items').each(function () {
          var row = rowOf($(this));
          if (row.address) out.push(row);
        });
        return out;
      },
      revalidate: validateAll,
      dispose: function () {
        closed = true;
        clearTimeout(timer);
      },
    };
    return api;
  };

  /**
   * The tag table of a read or write dialog, wired to its connection field:
   * rows revalidate when the connection changes. Returns the table.
   */
  editor.dialogTagTable = function (node) {
    var t = function (k, o) {
      return node._(k, o);
    };
    var urlOf = function () {
      return editor.urlOf($('#node-input-connection').val());
    };
    var table = editor.tagTable($('#node-input-plcwire-tags'), node.tags, urlOf, t);
    $('#node-input-connection').on('change', function () {
      table.revalidate();
    });
    return table;
  };

  /** Gives the tag table the dialog height the other rows leave. */
  editor.resizeTagTable = function (size) {
    var height = size.height;
    $('#dialog-form>div:not(.node-input-plcwire-tags-row)').each(function () {
      height -= $(this).outerHeight(true);
    });
    $('#node-input-plcwire-tags').editableList('height', Math.max(150, height - 40));
  };
})();
