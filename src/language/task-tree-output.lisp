;;;; Task tree output: JSON (yason) and a self-contained HTML page.

(in-package :cram-language)

(defun name-string (name)
  (cond ((null name) "")
        ((stringp name) name)
        ((symbolp name) (string-downcase (symbol-name name)))
        (t (princ-to-string name))))

(defun failure-json (plist)
  (when plist
    (alexandria:plist-hash-table
     (list "class" (string (getf plist :class))
           "description" (getf plist :description))
     :test #'equal)))

(defun node-json (node root-start)
  (alexandria:plist-hash-table
   (list "kind" (string-downcase (symbol-name (node-kind node)))
         "name" (name-string (node-name node))
         "designator" (node-designator node)
         "outcome" (string-downcase (symbol-name (node-outcome node)))
         "start_unix" (node-start-unix node)
         "end_unix" (node-end-unix node)
         "start_offset_s" (/ (- (node-start-time node) root-start)
                             1d6)
         "duration_s" (node-duration node)
         "failure" (failure-json (node-failure node))
         "caught_failures" (map 'vector #'failure-json (node-caught-failures node))
         "retries" (node-retries node)
         "pictures" (coerce (node-pictures node) 'vector)
         "children" (map 'vector (lambda (child) (node-json child root-start))
                         (node-children node)))
   :test #'equal))

(defun check-node (node who)
  (unless (typep node 'task-tree-node)
    (error "~a: expected a task tree node (e.g. CPL:*LAST-TASK-TREE*), got ~s."
           who node)))

(defun task-tree-to-json (&optional (root *last-task-tree*))
  "The task tree under ROOT (default: the last top-level run) as a JSON
string: each node an object with kind, name, designator, outcome, start_unix,
end_unix, start_offset_s, duration_s, failure {class, description},
caught_failures, retries and children."
  (check-node root 'task-tree-to-json)
  (with-output-to-string (stream)
    (yason:encode (node-json root (node-start-time root)) stream)))

;;; HTML

(defun html-escape (text)
  (with-output-to-string (out)
    (loop for char across (or text "")
          do (case char
               (#\< (write-string "&lt;" out))
               (#\> (write-string "&gt;" out))
               (#\& (write-string "&amp;" out))
               (#\" (write-string "&quot;" out))
               (t (write-char char out))))))

(defun format-duration (seconds)
  (cond ((< seconds 1d-3) (format nil "~,1f µs" (* seconds 1d6)))
        ((< seconds 1d0) (format nil "~,1f ms" (* seconds 1d3)))
        (t (format nil "~,2f s" seconds))))

(defparameter +task-tree-css+
  "body{font-family:sans-serif;margin:1.5em;color:#222}
h1{font-size:1.3em}
.summary span{margin-right:1.2em}
ul.tree{list-style:none;padding-left:1.4em;border-left:1px dotted #bbb;margin:0}
details>summary{cursor:pointer;padding:2px 0}
.leaf{padding:2px 0 2px 1.1em}
.kind{font-size:.8em;padding:1px 5px;border-radius:3px;background:#e4e4e4;margin-right:.4em}
.name{font-weight:bold}
.dur{color:#555;margin-left:.6em;font-size:.9em}
.outcome{font-size:.8em;padding:1px 6px;border-radius:3px;margin-left:.6em;color:#fff}
.succeeded{background:#2e7d32}.failed{background:#c62828}
.evaporated{background:#757575}.running{background:#ef6c00}
.row-failed>summary .name,.row-failed>.leaf .name{color:#c62828}
.desig{font-size:.85em;color:#1a237e;margin:2px 0 2px 1.2em}.desig pre{margin:2px 0;white-space:pre-wrap}
.pic{font-size:.85em;margin-left:.5em}
.info{font-size:.85em;margin:2px 0 2px 1.2em;color:#444}
.fail{color:#b71c1c}.caught{color:#8d6e63}.retries{color:#6a1b9a}")

(defun human-time (unix)
  "UNIX seconds as `2026-11-24 10:31:05.123 UTC'."
  (multiple-value-bind (seconds fraction) (floor unix)
    (multiple-value-bind (s mi h d mo y) (decode-universal-time (+ seconds (encode-universal-time 0 0 0 1 1 1970 0)) 0)
      (format nil "~d-~2,'0d-~2,'0d ~2,'0d:~2,'0d:~2,'0d.~3,'0d UTC" y mo d h mi s
              (min 999 (floor (* fraction 1000)))))))

(defun picture-link (path base)
  "PATH relative to the directory BASE when it lies below it, else PATH itself."
  (let ((dir (and base (namestring (uiop:pathname-directory-pathname base)))))
    (if (and dir (uiop:string-prefix-p dir path)) (subseq path (length dir)) path)))

(defun write-node-html (node root-start stream &optional base)
  (let* ((children (node-children node))
         (outcome (string-downcase (symbol-name (node-outcome node))))
         (header
           (format nil "<span class=\"kind\">~a</span><span class=\"name\">~a</span>~
                        <span class=\"outcome ~a\">~a</span>~
                        <span class=\"dur\">~a (at +~a)</span>~{ <a class=\"pic\" href=\"~a\">picture</a>~}"
                   (html-escape (string-downcase (symbol-name (node-kind node))))
                   (html-escape (name-string (node-name node)))
                   outcome outcome
                   (format-duration (node-duration node))
                   (format-duration (/ (- (node-start-time node) root-start)
                                       1d6))
                   (mapcar (lambda (p) (html-escape (picture-link p base))) (node-pictures node))))
         (details
           (with-output-to-string (out)
             (when (node-designator node)
               (format out "<details class=\"desig\"><summary>designator</summary><pre>~a</pre></details>"
                       (html-escape (node-designator node))))
             (when (node-failure node)
               (format out "<div class=\"info fail\">failure ~a: ~a</div>"
                       (html-escape (string (getf (node-failure node) :class)))
                       (html-escape (getf (node-failure node) :description))))
             (dolist (caught (node-caught-failures node))
               (format out "<div class=\"info caught\">caught ~a: ~a</div>"
                       (html-escape (string (getf caught :class)))
                       (html-escape (getf caught :description))))
             (when (plusp (node-retries node))
               (format out "<div class=\"info retries\">retries: ~d</div>"
                       (node-retries node))))))
    (format stream "<li class=\"row-~a\">" outcome)
    (if children
        (progn
          (format stream "<details open><summary>~a</summary>~a<ul class=\"tree\">"
                  header details)
          (dolist (child children)
            (write-node-html child root-start stream base))
          (format stream "</ul></details>"))
        (format stream "<div class=\"leaf\">~a</div>~a" header details))
    (format stream "</li>~%")))

(defun write-task-tree-html (path &optional (root *last-task-tree*))
  "Write the task tree under ROOT (default: the last top-level run) to PATH as
a self-contained HTML page: a collapsible indented tree with each node's kind,
name, outcome (coloured), duration, a link to each picture taken while it ran
(NOTE-PICTURE; relative to PATH's directory when below it), its designator
(collapsed), failure, caught failures and retries; times in UTC. Returns the
pathname written."
  (check-node root 'write-task-tree-html)
  (unless (or (stringp path) (pathnamep path))
    (error "WRITE-TASK-TREE-HTML: expected a path, got ~s." path))
  (let* ((nodes (find-task-tree-nodes (constantly t) root))
         (root-start (node-start-time root))
         (count (lambda (outcome) (count outcome nodes :key #'node-outcome))))
    (ensure-directories-exist path)
    (with-open-file (stream path :direction :output :if-exists :supersede
                                 :external-format :utf-8)
      (format stream "<!DOCTYPE html>~%<html><head><meta charset=\"utf-8\">~
                      <title>Task tree: ~a</title><style>~a</style></head><body>~%"
              (html-escape (name-string (node-name root))) +task-tree-css+)
      (format stream "<h1>Task tree of ~a</h1>~%<p class=\"summary\">~
                      <span>started ~a</span><span>duration ~a</span>~
                      <span>~d nodes</span><span>~d succeeded</span><span>~d failed</span>~
                      <span>~d evaporated</span><span>~d retries</span></p>~%"
              (html-escape (name-string (node-name root)))
              (human-time (node-start-unix root))
              (format-duration (node-duration root))
              (length nodes)
              (funcall count :succeeded) (funcall count :failed)
              (funcall count :evaporated)
              (reduce #'+ nodes :key #'node-retries))
      (format stream "<ul class=\"tree\">~%")
      (write-node-html root root-start stream path)
      (format stream "</ul>~%</body></html>~%"))
    (pathname path)))
